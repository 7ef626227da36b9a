// The editor's script language (editor/script.h): every action parses, and every bad line is an
// error naming the file and the line, found before anything runs.
#include "editor/script.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdio>
#include <string>

using namespace kaskad::editor;

namespace {

std::string error_of(const std::string& text) {
  auto r = parse_script_text(text, "s.txt");
  EXPECT_FALSE(r.ok()) << text;
  return r.ok() ? std::string() : r.error().to_string();
}

}  // namespace

TEST(EditorScript, EveryActionParses) {
  auto r = parse_script_text(
      "# a comment\n\nset sun.transform.direction=[0.2, -0.8, -0.3]\nselect box resting\n"
      "camera 1 2 3\ncamera 1 2 3 0 0 0\nkey ctrl+z\nview cascade\nframes 12\nscreenshot a.png\n"
      "window_screenshot w.png\nsave\nsave b.json\nundo\nredo\nquit\nquit!\r\n"
      "choices shadow.filter\nchoose sun.light.type point\ninput 5\n",
      "s.txt");
  ASSERT_TRUE(r.ok()) << r.error().to_string();
  ASSERT_EQ(r->size(), 18u);
  EXPECT_EQ((*r)[0].kind, ActionKind::set);
  EXPECT_EQ((*r)[0].args.at(0), "sun.transform.direction=[0.2, -0.8, -0.3]");  // spaces kept
  EXPECT_EQ((*r)[0].line, 3);
  EXPECT_EQ((*r)[1].args.at(0), "box resting");
  EXPECT_EQ((*r)[3].args.size(), 6u);
  EXPECT_EQ((*r)[5].kind, ActionKind::view);
  EXPECT_EQ((*r)[6].args.at(0), "12");
  EXPECT_TRUE((*r)[9].args.empty());
  EXPECT_EQ((*r)[13].kind, ActionKind::quit);
  EXPECT_EQ((*r)[14].kind, ActionKind::force_quit);
  EXPECT_EQ((*r)[15].kind, ActionKind::choices);
  EXPECT_EQ((*r)[15].args.at(0), "shadow.filter");
  EXPECT_EQ((*r)[16].kind, ActionKind::choose);
  EXPECT_EQ((*r)[16].args.size(), 2u);
  EXPECT_EQ((*r)[17].kind, ActionKind::input);
}

TEST(EditorScript, PanelInputParses) {
  auto r = parse_script_text(
      "click save as...\nctrl_click sun.light.intensity\ndouble_click entity:box resting\n"
      "drag make root -40\ntype 0.25 m\nkey enter\nkey escape\n",
      "s.txt");
  ASSERT_TRUE(r.ok()) << r.error().to_string();
  ASSERT_EQ(r->size(), 7u);
  EXPECT_EQ((*r)[0].kind, ActionKind::click);
  EXPECT_EQ((*r)[0].args, std::vector<std::string>{"save as..."});  // a label with a space
  EXPECT_EQ((*r)[1].kind, ActionKind::ctrl_click);
  EXPECT_EQ((*r)[2].kind, ActionKind::double_click);
  EXPECT_EQ((*r)[2].args, std::vector<std::string>{"entity:box resting"});
  EXPECT_EQ((*r)[3].kind, ActionKind::drag);
  EXPECT_EQ((*r)[3].args, (std::vector<std::string>{"make root", "-40"}));
  EXPECT_EQ((*r)[4].kind, ActionKind::type);
  EXPECT_EQ((*r)[4].args, std::vector<std::string>{"0.25 m"});
  EXPECT_EQ((*r)[5].args, std::vector<std::string>{"enter"});
  EXPECT_NE(error_of("drag sun.light.intensity\n").find("expected 'drag WIDGET PIXELS'"),
            std::string::npos);
  EXPECT_NE(error_of("drag sun.light.intensity far\n").find("drag: expected pixels"),
            std::string::npos);
  EXPECT_NE(error_of("click\n").find("expected 'click WIDGET'"), std::string::npos);
  // The keys a script presses, from the one table, in the message.
  for (const char* key : kScriptKeys)
    EXPECT_NE(error_of("key ctrl+q\n").find(key), std::string::npos) << key;
}

TEST(EditorScript, BadLinesNameTheFileAndLine) {
  EXPECT_EQ(error_of("frames 1\nsett a=1\n"),
            "s.txt: line 2: unknown action 'sett' (set, choices, choose, select, create, import, "
            "delete, duplicate, rename, parent, camera, orbit, key, click, ctrl_click, "
            "double_click, drag, type, view, frames, screenshot, "
            "window_screenshot, input, open, save, "
            "save_as, undo, redo, quit, quit!)");
  EXPECT_NE(error_of("orbit 10\n").find("line 1: expected 'orbit YAW_DEG PITCH_DEG'"),
            std::string::npos);
  EXPECT_NE(error_of("orbit 10 up\n").find("orbit: 'up' is not a number"), std::string::npos);
  EXPECT_NE(error_of("set shadow.cascade_count\n").find("line 1: expected 'set KEY=VALUE'"),
            std::string::npos);
  EXPECT_NE(error_of("camera 1 2\n").find("line 1: expected 'camera X Y Z"), std::string::npos);
  EXPECT_NE(error_of("camera 1 2 3 4\n").find("line 1: expected 'camera"), std::string::npos);
  EXPECT_NE(error_of("camera 1 2 x\n").find("'x' is not a number"), std::string::npos);
  EXPECT_NE(error_of("camera 1 2 nan\n").find("'nan' is not a number"), std::string::npos);
  EXPECT_NE(error_of("key ctrl+q\n").find("unknown key 'ctrl+q'"), std::string::npos);
  EXPECT_NE(error_of("view shadows\n").find("unknown view 'shadows'"), std::string::npos);
  // The message lists every view, from the views' one table.
  for (const char* name : kViewNames)
    EXPECT_NE(error_of("view shadows\n").find(name), std::string::npos) << name;
  EXPECT_NE(error_of("frames 0\n").find("[1, 100000]"), std::string::npos);
  EXPECT_NE(error_of("input 0\n").find("input: expected seconds in [1, 600], got '0'"),
            std::string::npos);
  EXPECT_NE(error_of("input 2.5\n").find("got '2.5'"), std::string::npos);
  EXPECT_NE(error_of("frames 3x\n").find("'3x'"), std::string::npos);
  EXPECT_NE(error_of("undo now\n").find("expected 'undo'"), std::string::npos);
  EXPECT_NE(error_of("screenshot\n").find("expected 'screenshot PATH.png'"), std::string::npos);
  EXPECT_NE(error_of("save a b\n").find("expected 'save [PATH]'"), std::string::npos);
}

TEST(EditorScript, NamedPipeIsRefusedUnopened) {
  // Opening a named pipe waits for a writer: the script is refused by its kind instead.
  const std::string pipe = std::string(::testing::TempDir()) + "kaskad_script_pipe.txt";
  std::remove(pipe.c_str());
  ASSERT_EQ(mkfifo(pipe.c_str(), 0600), 0);
  auto r = parse_script(pipe);
  std::remove(pipe.c_str());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().to_string(),
            pipe + ": not a regular file but a named pipe (FIFO); kaskad reads only regular files");
}

TEST(EditorScript, MissingFileIsAnError) {
  auto r = parse_script("/nonexistent/script.txt");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().to_string(), "/nonexistent/script.txt: cannot open the script");
}
