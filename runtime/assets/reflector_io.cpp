#include "runtime/assets/reflector_io.h"

#include "runtime/core/field_io.h"

namespace kaskad {
namespace {

using json = nlohmann::json;
using json_reader::fail;
using json_reader::type_name;
using json_reader::vec;

}  // namespace

void read_reflector(json_reader::ObjectReader& r, Reflector& out) {
  field_io::read_fields(r, out);
  // center: [x, y, z], or "auto" (the centre of the entity's bounds; what a file without it gets).
  if (r.has("center") && r.raw("center").is_string()) {
    if (r.raw("center") != "auto")
      fail(r.at("center"), "expected [x, y, z] or \"auto\", got " + r.raw("center").dump());
    out.has_center = false;
  } else if (r.has("center")) {
    r.vector<3>("center", out.center, -kMaxCoordinate, kMaxCoordinate);
    out.has_center = true;
  }
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
    br.vector<3>("min", out.box_min, -kMaxCoordinate, kMaxCoordinate);
    br.vector<3>("max", out.box_max, -kMaxCoordinate, kMaxCoordinate);
    br.finish();
    out.box_projection = true;
  }
  r.finish();
  if (std::string bad = validate_reflector(out); !bad.empty())
    fail(r.at(bad.substr(0, bad.find(' ')).c_str()), bad);
}

Result<CubeMap> load_static_env_map(const std::filesystem::path& file, const Reflector& r) {
  EnvLoadOptions options;
  options.layout = r.layout;
  options.z_up_3dsmax = r.z_up_3dsmax;
  options.face_size = r.resolution;
  return load_cube_map(file, options);
}

json reflector_to_json(const Reflector& r) {
  json j = field_io::write_fields(r);
  j["center"] = r.has_center ? vec(r.center) : json("auto");
  json layers = json::array();
  for (int i = 0; i < 32; ++i)
    if (r.exclude_layers & (1u << i)) layers.push_back(i);
  j["exclude_layers"] = layers;
  j["box"] =
      r.box_projection ? json{{"min", vec(r.box_min)}, {"max", vec(r.box_max)}} : json("none");
  return j;
}

}  // namespace kaskad
