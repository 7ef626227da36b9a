#include "runtime/assets/reflector_io.h"

namespace kaskad {
namespace {

using json = nlohmann::json;
using json_reader::enum_name;
using json_reader::fail;
using json_reader::num;
using json_reader::type_name;
using json_reader::vec;

const std::vector<std::pair<const char*, ReflectionMap>> kMaps = {
    {"cube", ReflectionMap::cube}, {"sphere", ReflectionMap::sphere}};
const std::vector<std::pair<const char*, ProbeUpdate>> kUpdates = {
    {"static_file", ProbeUpdate::static_file}, {"first_frame", ProbeUpdate::first_frame},
    {"every_n", ProbeUpdate::every_n}, {"on_change", ProbeUpdate::on_change}};
const std::vector<std::pair<const char*, EnvLayoutName>> kLayouts = {
    {"auto", EnvLayoutName::auto_detect}, {"faces", EnvLayoutName::faces}, {"horizontal_cross", EnvLayoutName::horizontal_cross},
    {"vertical_cross", EnvLayoutName::vertical_cross}, {"equirect", EnvLayoutName::equirect},
    {"sphere", EnvLayoutName::sphere}};

constexpr float kBig = 1.0e7f;  // as scene_io.cpp

}  // namespace

void read_reflector(json_reader::ObjectReader& r, Reflector& out) {
  r.enumeration("map", out.map, kMaps);
  r.enumeration("update", out.update, kUpdates);
  r.integer("every_n", out.every_n, 1, 1 << 20);
  r.integer("faces_per_frame", out.faces_per_frame, 1, 6);
  r.power_of_two("resolution", out.resolution, 8, 2048);
  // center: [x, y, z], or "auto" (the centre of the entity's bounds; what a file without it gets).
  if (r.has("center") && r.raw("center").is_string()) {
    if (r.raw("center") != "auto")
      fail(r.at("center"), "expected [x, y, z] or \"auto\", got " + r.raw("center").dump());
    out.has_center = false;
  } else if (r.has("center")) {
    r.vector<3>("center", out.center, -kBig, kBig);
    out.has_center = true;
  }
  r.number("near", out.near, 1e-6f, kBig);
  r.number("far", out.far, 1e-6f, kBig);
  if (r.has("exclude_layers")) {
    const json& list = r.raw("exclude_layers");
    if (!list.is_array()) fail(r.at("exclude_layers"), "expected an array of layers, got " + type_name(list));
    out.exclude_layers = 0;
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string at = r.at("exclude_layers") + "/" + std::to_string(i);
      if (!list[i].is_number_integer()) fail(at, "expected a layer in [0, 31], got " + type_name(list[i]));
      const long long layer = list[i].get<long long>();
      if (layer < 0 || layer > 31) fail(at, "layer must be in [0, 31], was " + std::to_string(layer));
      out.exclude_layers |= 1u << layer;
    }
  }
  // box: {"min": [x, y, z], "max": [x, y, z]}, or "none" (no box projection; a file without it).
  if (r.has("box") && r.raw("box").is_string()) {
    if (r.raw("box") != "none")
      fail(r.at("box"), "expected {\"min\": [x, y, z], \"max\": [x, y, z]} or \"none\", got " +
                            r.raw("box").dump());
    out.box_projection = false;
  } else if (r.has("box")) {
    json_reader::ObjectReader br(r.raw("box"), r.at("box"));
    if (!br.has("min") || !br.has("max")) fail(r.at("box"), "a box needs min and max");
    br.vector<3>("min", out.box_min, -kBig, kBig);
    br.vector<3>("max", out.box_max, -kBig, kBig);
    br.finish();
    out.box_projection = true;
  }
  r.number("amount", out.amount, 0.0f, 1.0f);
  r.string("file", out.file);
  r.enumeration("layout", out.layout, kLayouts);
  r.boolean("z_up_3dsmax", out.z_up_3dsmax);
  r.finish();
  if (std::string bad = validate_reflector(out); !bad.empty())
    fail(r.at(bad.substr(0, bad.find(' ')).c_str()), bad);
}

Result<CubeMap> load_static_env_map(const std::filesystem::path& file, const Reflector& r) {
  EnvLoadOptions options;
  switch (r.layout) {
    case EnvLayoutName::auto_detect: options.layout = EnvLayout::auto_detect; break;
    case EnvLayoutName::faces: options.layout = EnvLayout::faces; break;
    case EnvLayoutName::horizontal_cross: options.layout = EnvLayout::horizontal_cross; break;
    case EnvLayoutName::vertical_cross: options.layout = EnvLayout::vertical_cross; break;
    case EnvLayoutName::equirect: options.layout = EnvLayout::equirect; break;
    case EnvLayoutName::sphere: options.layout = EnvLayout::sphere; break;
  }
  options.z_up_3dsmax = r.z_up_3dsmax;
  options.face_size = r.resolution;
  return load_cube_map(file, options);
}

json reflector_to_json(const Reflector& r) {
  json j = {{"map", enum_name(r.map, kMaps)},
            {"update", enum_name(r.update, kUpdates)},
            {"every_n", r.every_n},
            {"faces_per_frame", r.faces_per_frame},
            {"resolution", r.resolution}};
  j["center"] = r.has_center ? vec(r.center) : json("auto");
  j["near"] = num(r.near);
  j["far"] = num(r.far);
  json layers = json::array();
  for (int i = 0; i < 32; ++i)
    if (r.exclude_layers & (1u << i)) layers.push_back(i);
  j["exclude_layers"] = layers;
  j["box"] =
      r.box_projection ? json{{"min", vec(r.box_min)}, {"max", vec(r.box_max)}} : json("none");
  j["amount"] = num(r.amount);
  j["file"] = r.file;
  j["layout"] = enum_name(r.layout, kLayouts);
  j["z_up_3dsmax"] = r.z_up_3dsmax;
  return j;
}

}  // namespace kaskad
