#include "editor/script.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "runtime/core/file_io.h"

namespace kaskad::editor {

namespace {

bool is_number(const std::string& s) {
  float v = 0.0f;
  auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && ptr == s.data() + s.size() && std::isfinite(v);
}

// A whole decimal number in [lo, hi], nothing else.
bool whole_number_in(const std::string& s, int lo, int hi) {
  int v = 0;
  auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && ptr == s.data() + s.size() && v >= lo && v <= hi;
}

// A table's names joined by `separator`: messages list what the one table holds.
template <class Table, class NameOf>
std::string names_of(const Table& table, const char* separator, NameOf name_of) {
  std::string out;
  for (const auto& entry : table) {
    if (!out.empty()) out += separator;
    out += name_of(entry);
  }
  return out;
}
const char* itself(const char* name) {
  return name;
}

struct Verb {
  const char* name;
  ActionKind kind;
  int min_args, max_args;
  const char* usage;
};

constexpr Verb kVerbs[] = {
    {"set", ActionKind::set, 1, 1, "set KEY=VALUE"},
    {"choices", ActionKind::choices, 1, 1, "choices KEY"},
    {"choose", ActionKind::choose, 2, 2, "choose KEY NAME"},
    {"select", ActionKind::select, 1, 1, "select NAME"},
    {"create", ActionKind::create, 1, 1, "create SHAPE (box, sphere, cylinder, cone, plane)"},
    {"import", ActionKind::import, 1, 1, "import MODEL.gltf|.glb"},
    {"delete", ActionKind::remove, 0, 0, "delete"},
    {"duplicate", ActionKind::duplicate, 0, 0, "duplicate"},
    {"rename", ActionKind::rename, 1, 1, "rename NAME"},
    {"parent", ActionKind::parent, 1, 1, "parent NAME (or - for none)"},
    {"camera", ActionKind::camera, 3, 6, "camera X Y Z [LOOK_X LOOK_Y LOOK_Z]"},
    {"orbit", ActionKind::orbit, 2, 2, "orbit YAW_DEG PITCH_DEG"},
    {"key", ActionKind::key, 1, 1, "key K"},
    {"click", ActionKind::click, 1, 1, "click WIDGET"},
    {"ctrl_click", ActionKind::ctrl_click, 1, 1, "ctrl_click WIDGET"},
    {"double_click", ActionKind::double_click, 1, 1, "double_click WIDGET"},
    {"drag", ActionKind::drag, 2, 2, "drag WIDGET PIXELS"},
    {"type", ActionKind::type, 1, 1, "type TEXT"},
    {"view", ActionKind::view, 1, 1, "view VIEW"},
    {"frames", ActionKind::frames, 1, 1, "frames N (1..100000)"},
    {"screenshot", ActionKind::screenshot, 1, 1, "screenshot PATH.png"},
    {"window_screenshot", ActionKind::window_screenshot, 1, 1, "window_screenshot PATH.png"},
    {"input", ActionKind::input, 1, 1, "input SECONDS (1..600)"},
    {"open", ActionKind::open, 1, 1, "open SCENE"},
    {"save", ActionKind::save, 0, 1, "save [PATH]"},
    {"save_as", ActionKind::save_as, 1, 1, "save_as PATH"},
    {"undo", ActionKind::undo, 0, 0, "undo"},
    {"redo", ActionKind::redo, 0, 0, "redo"},
    {"quit", ActionKind::quit, 0, 0, "quit"},
    {"quit!", ActionKind::force_quit, 0, 0, "quit!"},
};

}  // namespace

bool is_script_key(const std::string& name) {
  for (const char* k : kScriptKeys)
    if (name == k) return true;
  return false;
}

Result<std::vector<ScriptAction>> parse_script_text(const std::string& text,
                                                    const std::filesystem::path& file) {
  std::vector<ScriptAction> actions;
  std::istringstream in(text);
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string verb;
    if (!(words >> verb) || verb[0] == '#') continue;
    const std::string where = "line " + std::to_string(n);
    const Verb* v = nullptr;
    for (const Verb& candidate : kVerbs)
      if (verb == candidate.name) v = &candidate;
    if (!v) {
      const std::string known = names_of(kVerbs, ", ", [](const Verb& v) { return v.name; });
      return Error{file.string(), where, "unknown action '" + verb + "' (" + known + ")"};
    }
    ScriptAction a;
    a.kind = v->kind;
    a.line = n;
    if (a.kind == ActionKind::set || a.kind == ActionKind::select || a.kind == ActionKind::rename ||
        a.kind == ActionKind::parent || a.kind == ActionKind::type || a.kind == ActionKind::click ||
        a.kind == ActionKind::ctrl_click || a.kind == ActionKind::double_click) {
      // The rest of the line, spaces included: a value may be a JSON array or a name with spaces.
      std::string rest;
      std::getline(words, rest);
      const auto first = rest.find_first_not_of(" \t");
      const auto last = rest.find_last_not_of(" \t");
      if (first != std::string::npos) a.args.push_back(rest.substr(first, last - first + 1));
    } else {
      for (std::string w; words >> w;) a.args.push_back(w);
      // drag WIDGET PIXELS: the widget's name may hold spaces ("make root").
      while (a.kind == ActionKind::drag && a.args.size() > 2) {
        a.args[0] += " " + a.args[1];
        a.args.erase(a.args.begin() + 1);
      }
    }
    const int count = int(a.args.size());
    if (count < v->min_args || count > v->max_args || (a.kind == ActionKind::camera && count == 4) ||
        (a.kind == ActionKind::camera && count == 5))
      return Error{file.string(), where, std::string("expected '") + v->usage + "'"};
    if (a.kind == ActionKind::set && a.args[0].find('=') == std::string::npos)
      return Error{file.string(), where, "expected 'set KEY=VALUE', got 'set " + a.args[0] + "'"};
    if (a.kind == ActionKind::camera || a.kind == ActionKind::orbit)
      for (const std::string& c : a.args)
        if (!is_number(c))
          return Error{file.string(), where, verb + ": '" + c + "' is not a number"};
    if (a.kind == ActionKind::key && !is_script_key(a.args[0]))
      return Error{file.string(), where,
                   "unknown key '" + a.args[0] + "'; expected one of " +
                       names_of(kScriptKeys, ", ", itself)};
    if (a.kind == ActionKind::view && !view_named(a.args[0]))
      return Error{
          file.string(), where,
          "unknown view '" + a.args[0] + "'; expected view " + names_of(kViewNames, "|", itself)};
    if (a.kind == ActionKind::drag && !whole_number_in(a.args[1], -100000, 100000))
      return Error{file.string(), where,
                   "drag: expected pixels in [-100000, 100000], got '" + a.args[1] + "'"};
    if (a.kind == ActionKind::input && !whole_number_in(a.args[0], 1, 600))
      return Error{file.string(), where, "input: expected seconds in [1, 600], got '" + a.args[0] + "'"};
    if (a.kind == ActionKind::frames && !whole_number_in(a.args[0], 1, 100000))
      return Error{file.string(), where,
                   "frames: expected a count in [1, 100000], got '" + a.args[0] + "'"};
    actions.push_back(std::move(a));
  }
  return actions;
}

Result<std::vector<ScriptAction>> parse_script(const std::filesystem::path& file) {
  if (std::string why = special_file_error(file); !why.empty()) return Error{file.string(), "", why};
  std::ifstream in(file, std::ios::binary);
  if (!in) return Error{file.string(), "", "cannot open the script"};
  std::stringstream text;
  text << in.rdbuf();
  if (in.bad()) return Error{file.string(), "", "cannot read the script"};
  return parse_script_text(text.str(), file);
}

}  // namespace kaskad::editor
