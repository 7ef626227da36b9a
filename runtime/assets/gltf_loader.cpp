// glTF 2.0 import: tinygltf parses the JSON and loads buffers; this file validates everything it
// uses (indices, byte ranges, counts, numbers) before touching data, decodes
// KHR_draco_mesh_compression itself with libdraco (see tinygltf_config.h for why), and turns the
// default scene into entities. The steps live in gltf_parse.cpp (1-2), gltf_geometry.cpp and
// gltf_materials.cpp (meshes and materials, converted on first use) and here (3-5). Content errors come back as Error and never abort (STYLE.md 10).
//
// The import, step by step (import_gltf):
//   1. read the file and refuse what tinygltf cannot parse safely (size, JSON nesting);
//   2. parse with tinygltf; URI images are decoded by our callback through OIIO, images stored in
//      buffer views later, once their view is range-checked;
//   3. refuse files that require extensions we do not implement;
//   4. validate the node hierarchy (indices, single parent) and pick the root nodes;
//   5. walk the hierarchy parents-first, creating node entities, primitive child entities (meshes
//      and materials are converted once, on first use) and lights and cameras;
//   6. bind skinned primitives to their skins and import animations (gltf_animation.cpp).
#include "runtime/assets/gltf_loader.h"

#include <cmath>
#include <limits>
#include <numbers>

#include <glm/gtc/quaternion.hpp>

#include "components/animation.h"
#include "components/camera.h"
#include "components/light.h"
#include "components/model.h"
#include "components/name.h"
#include "components/shadow_settings.h"
#include "components/transform.h"
#include "runtime/assets/gltf_internal.h"

namespace kaskad {
namespace {

using namespace gltf_detail;

// ---- Scene conversion -----------------------------------------------------------------------

const std::vector<ImportedPrimitive>* find_or_import_mesh(Importer& im, int mesh_index,
                                                          Error& error) {
  if (auto it = im.meshes.find(mesh_index); it != im.meshes.end()) return &it->second;
  const tinygltf::Mesh& mesh = im.model.meshes[std::size_t(mesh_index)];
  std::vector<ImportedPrimitive> out;
  for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
    auto data = read_primitive(im.model, im.file, mesh_index, int(p), im.report.warnings);
    if (!data) {
      error = data.error();
      return nullptr;
    }
    if (!data->has_value()) continue;
    im.report.triangles += (*data)->triangle_count();
    out.push_back({im.assets.add_mesh(std::move(**data)), mesh.primitives[p].material, int(p)});
  }
  return &(im.meshes[mesh_index] = std::move(out));
}

/// Decodes an image stored in a buffer view (after range-checking the view).

Transform decompose_node_matrix(const glm::mat4& matrix, std::vector<std::string>& warnings,
                                const std::string& where) {
  const Transform t = decompose(matrix);
  if (matrix[0][3] != 0.0f || matrix[1][3] != 0.0f || matrix[2][3] != 0.0f ||
      matrix[3][3] != 1.0f) {
    warnings.push_back(where + ": matrix is not affine; its projective part is ignored");
  }
  if (!(std::min({std::abs(t.scale.x), std::abs(t.scale.y), std::abs(t.scale.z)}) > 1e-12f))
    return t;  // a zero scale: no rotation recovered, no shear to speak of
  glm::vec3 axis[3] = {glm::vec3(matrix[0]), glm::vec3(matrix[1]), glm::vec3(matrix[2])};
  for (glm::vec3& a : axis) a = glm::normalize(a);
  const float shear =
      std::max({std::abs(glm::dot(axis[0], axis[1])), std::abs(glm::dot(axis[1], axis[2])),
                std::abs(glm::dot(axis[0], axis[2]))});
  if (shear > 1e-3f) warnings.push_back(where + ": matrix has shear; it is approximated");
  return t;
}

/// The node's local transform from TRS or matrix (parent is set by the caller).
Result<Transform> node_transform(const Importer& im, int index,
                                 std::vector<std::string>& warnings) {
  const tinygltf::Node& node = im.model.nodes[std::size_t(index)];
  const std::string where = label("nodes", index, node.name);
  const auto& t = node.translation;
  const auto& r = node.rotation;
  const auto& s = node.scale;
  const auto& m = node.matrix;
  if (!(t.empty() || t.size() == 3) || !(r.empty() || r.size() == 4) ||
      !(s.empty() || s.size() == 3) || !(m.empty() || m.size() == 16)) {
    return Error{im.file, where, "translation, rotation, scale or matrix has the wrong length"};
  }
  if (!all_finite(t) || !all_finite(r) || !all_finite(s) || !all_finite(m)) {
    return Error{im.file, where, "non-finite transform value"};
  }
  if (m.size() == 16) {
    glm::mat4 matrix;
    for (int c = 0; c < 4; ++c)
      for (int row = 0; row < 4; ++row) matrix[c][row] = float(m[std::size_t(c * 4 + row)]);
    return decompose_node_matrix(matrix, warnings, where);
  }
  Transform out;
  if (t.size() == 3) out.translation = {float(t[0]), float(t[1]), float(t[2])};
  if (s.size() == 3) out.scale = {float(s[0]), float(s[1]), float(s[2])};
  if (r.size() == 4) {
    const glm::quat q{float(r[3]), float(r[0]), float(r[1]), float(r[2])};  // glTF: x, y, z, w
    const float len = glm::length(q);
    if (!(len > 1e-6f)) return Error{im.file, where, "rotation quaternion has zero length"};
    out.rotation = q / len;
  }
  return out;
}

/// KHR_lights_punctual light -> Light (+ ShadowSettings for directional lights).
Status add_light(Importer& im, ecs::Entity entity, int node_index, const tinygltf::Value& ext) {
  const std::string node_where = label("nodes", node_index, im.model.nodes[node_index].name);
  int index = -1;
  const tinygltf::Value* light_value = member(ext, "light");
  if (light_value == nullptr || !as_index(*light_value, index) ||
      std::size_t(index) >= im.model.lights.size()) {
    return Error{im.file, node_where + " KHR_lights_punctual",
                 "light index missing or out of range (" + std::to_string(im.model.lights.size()) +
                     " lights)"};
  }
  const tinygltf::Light& g = im.model.lights[std::size_t(index)];
  const std::string where = "KHR_lights_punctual " + label("lights", index, g.name);

  Light light;
  if (g.type == "directional") {
    light.type = LightType::directional;
  } else if (g.type == "spot") {
    light.type = LightType::spot;
  } else if (g.type == "point") {
    light.type = LightType::point;
  } else {
    return Error{im.file, where, "unknown light type \"" + g.type + "\""};
  }
  if (!(g.color.empty() || g.color.size() == 3) || !all_finite(g.color) ||
      std::any_of(g.color.begin(), g.color.end(), [](double c) { return c < 0.0; })) {
    return Error{im.file, where, "color must be 3 finite numbers >= 0"};
  }
  if (g.color.size() == 3) light.color = {float(g.color[0]), float(g.color[1]), float(g.color[2])};
  if (!(std::isfinite(g.intensity) && g.intensity >= 0.0)) {
    return Error{im.file, where, "intensity must be a finite number >= 0"};
  }
  light.intensity = float(g.intensity);
  if (!(std::isfinite(g.range) && g.range >= 0.0)) {
    return Error{im.file, where, "range must be a finite number >= 0 (0: infinite)"};
  }
  light.range = light.type == LightType::directional ? 0.0f : float(g.range);
  if (light.type == LightType::spot) {
    const double inner = g.spot.innerConeAngle, outer = g.spot.outerConeAngle;
    if (!(inner >= 0.0 && inner <= outer && outer > 0.0 && outer <= std::numbers::pi / 2)) {
      return Error{im.file, where,
                   "spot cone angles must satisfy 0 <= inner <= outer <= pi/2, "
                   "were " +
                       std::to_string(inner) + " and " + std::to_string(outer)};
    }
    light.inner_cone_deg = float(inner * 180.0 / std::numbers::pi);
    light.outer_cone_deg = float(outer * 180.0 / std::numbers::pi);
  }
  if (light.type == LightType::directional) {
    light.cast_shadows = true;
    im.world.emplace<ShadowSettings>(entity, ShadowSettings{});
  }
  im.world.emplace<Light>(entity, light);
  ++im.report.lights;
  return {};
}

/// glTF camera -> Camera. An infinite perspective far plane becomes near * kInfiniteFarOverNear.
Status add_camera(Importer& im, ecs::Entity entity, int camera_index) {
  if (std::size_t(camera_index) >= im.model.cameras.size()) {
    return Error{im.file, "",
                 "camera " + std::to_string(camera_index) + " out of range (" +
                     std::to_string(im.model.cameras.size()) + " cameras)"};
  }
  const tinygltf::Camera& g = im.model.cameras[std::size_t(camera_index)];
  const std::string where = label("cameras", camera_index, g.name);
  Camera camera;
  if (g.type == "perspective") {
    const auto& p = g.perspective;
    if (!(std::isfinite(p.yfov) && p.yfov > 0.0 && p.yfov < std::numbers::pi)) {
      return Error{im.file, where,
                   "yfov must be in (0, pi) radians, was " + std::to_string(p.yfov)};
    }
    if (!(std::isfinite(p.znear) && p.znear > 0.0)) {
      return Error{im.file, where, "znear must be > 0, was " + std::to_string(p.znear)};
    }
    if (!(std::isfinite(p.zfar) && (p.zfar == 0.0 || p.zfar > p.znear))) {
      return Error{im.file, where, "zfar must be > znear, was " + std::to_string(p.zfar)};
    }
    if (!(std::isfinite(p.aspectRatio) && p.aspectRatio >= 0.0)) {
      return Error{im.file, where, "aspectRatio must be > 0"};
    }
    camera.projection = Projection::perspective;
    camera.fov_y_deg = float(p.yfov * 180.0 / std::numbers::pi);
    camera.near = float(p.znear);
    camera.far = p.zfar == 0.0 ? camera.near * kInfiniteFarOverNear : float(p.zfar);
    camera.aspect = float(p.aspectRatio);
  } else if (g.type == "orthographic") {
    const auto& o = g.orthographic;
    if (!(std::isfinite(o.xmag) && std::isfinite(o.ymag) && o.xmag != 0.0 && o.ymag != 0.0)) {
      return Error{im.file, where, "xmag and ymag must be finite and non-zero"};
    }
    if (!(std::isfinite(o.znear) && std::isfinite(o.zfar) && o.znear >= 0.0 && o.zfar > o.znear)) {
      return Error{im.file, where, "orthographic planes must satisfy 0 <= znear < zfar"};
    }
    camera.projection = Projection::orthographic;
    camera.ortho_height = float(2.0 * std::abs(o.ymag));
    camera.aspect = float(std::abs(o.xmag / o.ymag));
    // Camera requires near > 0; glTF allows 0 for orthographic views.
    camera.near = o.znear > 0.0 ? float(o.znear) : float(o.zfar * 1e-6);
    camera.far = float(o.zfar);
  } else {
    return Error{im.file, where, "unknown camera type \"" + g.type + "\""};
  }
  if (im.activate_first_camera && !im.camera_activated) {
    camera.active = true;
    im.camera_activated = true;
  }
  im.world.emplace<Camera>(entity, camera);
  ++im.report.cameras;
  return {};
}

/// Creates the entity of node `index` under `parent`, with its primitives, light and camera.
Result<ecs::Entity> import_node(Importer& im, int index, ecs::Entity parent) {
  const tinygltf::Node& node = im.model.nodes[std::size_t(index)];
  const std::string where = label("nodes", index, node.name);
  auto transform = node_transform(im, index, im.report.warnings);
  if (!transform) return transform.error();
  const std::string name = node.name.empty() ? "node_" + std::to_string(index) : node.name;

  const ecs::Entity entity = im.world.create();
  transform->parent = parent;
  im.world.emplace<Name>(entity, Name{name});
  im.world.emplace<Transform>(entity, transform.value());
  im.world.emplace<Imported>(entity, Imported{im.source});
  ++im.report.nodes;

  if (node.mesh >= 0) {
    if (std::size_t(node.mesh) >= im.model.meshes.size()) {
      return Error{im.file, where,
                   "mesh " + std::to_string(node.mesh) + " out of range (" +
                       std::to_string(im.model.meshes.size()) + " meshes)"};
    }
    Error error;
    const auto* primitives = find_or_import_mesh(im, node.mesh, error);
    if (primitives == nullptr) return error;
    for (const ImportedPrimitive& p : *primitives) {
      auto material = read_material(im, p.material);
      if (!material) {
        Error e = material.error();
        if (e.where.empty())
          e.where = label("meshes", node.mesh) + " primitives[" + std::to_string(p.primitive) + "]";
        return e;
      }
      const ecs::Entity child = im.world.create();
      Transform local;
      local.parent = entity;
      im.world.emplace<Name>(child, Name{name + "/prim" + std::to_string(p.primitive)});
      im.world.emplace<Transform>(child, local);
      MeshRenderer renderer;
      renderer.mesh = p.mesh;
      im.world.emplace<MeshRenderer>(child, renderer);
      im.world.emplace<Material>(child, material.value());
      im.world.emplace<Imported>(child, Imported{im.source});
      ++im.report.mesh_entities;
      const MeshDeform& deform = im.assets.meshes[kaskad::index(p.mesh)].deform;
      if (deform.skinned() && node.skin >= 0) {
        im.skinned.push_back({child, index, p.mesh});
      } else if (deform.skinned()) {
        im.report.warnings.push_back(where + ": mesh has joint weights but the node no skin; "
                                             "drawn in its bind pose");
      }
      if (deform.morphed()) {
        ++im.report.morphed;
        if (!(deform.skinned() && node.skin >= 0)) im.world.emplace<Deformer>(child);
      }
    }
    // The node's morph weights: its own, else its mesh's (glTF 2.0, 3.7.2.2).
    const tinygltf::Mesh& mesh = im.model.meshes[std::size_t(node.mesh)];
    std::size_t targets = 0;
    for (const auto& prim : mesh.primitives) targets = std::max(targets, prim.targets.size());
    if (targets > 0) {
      MorphWeights w;
      w.weights.assign(targets, 0.0f);
      const std::vector<double>& given = node.weights.empty() ? mesh.weights : node.weights;
      if (!given.empty() && given.size() != targets)
        return Error{im.file, where, "weights has " + std::to_string(given.size()) +
                                         " values for " + std::to_string(targets) +
                                         " morph targets"};
      for (std::size_t t = 0; t < given.size(); ++t) {
        if (!std::isfinite(given[t])) return Error{im.file, where, "weights must be finite"};
        w.weights[t] = float(given[t]);
      }
      im.world.emplace<MorphWeights>(entity, std::move(w));
    }
  }
  if (node.skin >= 0 && node.mesh < 0)
    im.report.warnings.push_back(where + ": skin without a mesh ignored");
  if (node.skin >= 0 && node.mesh >= 0) {
    bool any = false;
    for (const auto& s : im.skinned) any = any || s.node == index;
    if (!any)
      im.report.warnings.push_back(where + ": skin ignored: its mesh has no JOINTS_0 and WEIGHTS_0 "
                                           "(drawn in its bind pose)");
  }
  im.node_entities[std::size_t(index)] = entity;
  if (node.camera >= 0) KASKAD_TRY(add_camera(im, entity, node.camera));
  if (auto ext = node.extensions.find("KHR_lights_punctual"); ext != node.extensions.end())
    KASKAD_TRY(add_light(im, entity, index, ext->second));
  return entity;
}

/// Checks child indices and single parents; returns the nodes to import as roots.
Result<std::vector<int>> root_nodes(const tinygltf::Model& model, const std::string& file) {
  const std::size_t count = model.nodes.size();
  std::vector<int> parent(count, -1);
  for (std::size_t n = 0; n < count; ++n) {
    for (int child : model.nodes[n].children) {
      const std::string where = label("nodes", int(n), model.nodes[n].name);
      if (child < 0 || std::size_t(child) >= count) {
        return Error{file, where,
                     "child " + std::to_string(child) + " out of range (" + std::to_string(count) +
                         " nodes)"};
      }
      if (parent[std::size_t(child)] != -1 || std::size_t(child) == n) {
        return Error{file, where,
                     "node " + std::to_string(child) +
                         " has more than one parent (the hierarchy must be a tree)"};
      }
      parent[std::size_t(child)] = int(n);
    }
  }
  std::vector<int> roots;
  if (model.defaultScene >= 0) {
    if (std::size_t(model.defaultScene) >= model.scenes.size()) {
      return Error{file, "scene",
                   "default scene " + std::to_string(model.defaultScene) + " out of range (" +
                       std::to_string(model.scenes.size()) + " scenes)"};
    }
    const std::string where = label("scenes", model.defaultScene);
    std::set<int> seen;
    for (int n : model.scenes[std::size_t(model.defaultScene)].nodes) {
      if (n < 0 || std::size_t(n) >= count) {
        return Error{file, where, "node " + std::to_string(n) + " out of range"};
      }
      if (parent[std::size_t(n)] != -1 || !seen.insert(n).second) {
        return Error{file, where,
                     "node " + std::to_string(n) + " is not a root node or is listed twice"};
      }
      roots.push_back(n);
    }
  } else {
    for (std::size_t n = 0; n < count; ++n)
      if (parent[n] == -1) roots.push_back(int(n));
  }
  // Nodes in a parent cycle have a parent each, so they are never reached from a root: walking
  // down from the roots visits every node at most once.
  return roots;
}

Status check_extensions(const tinygltf::Model& model, const std::string& file,
                        std::vector<std::string>& warnings) {
  // glTF 2.0, 3.2: a file of another major version may not be read as this one.
  const std::string& version = model.asset.version;
  if (version.rfind("2.", 0) != 0)
    return Error{file, "asset.version",
                 "glTF version '" + version + "': only 2.x files are read"};
  if (const std::string& min = model.asset.minVersion; !min.empty() && min != "2.0")
    return Error{file, "asset.minVersion",
                 "the file needs glTF " + min + " at least; this reader knows 2.0"};
  for (const std::string& ext : model.extensionsRequired) {
    if (ext == "EXT_texture_avif")
      return Error{file, "extensionsRequired",
                   "the file requires EXT_texture_avif: AVIF images are not decoded here and it "
                   "gives no fallback images; convert its textures to PNG, JPEG or WebP"};
    if (!supported_extension(ext)) {
      return Error{file, "extensionsRequired", "unsupported required extension " + ext};
    }
  }
  std::string ignored;
  for (const std::string& ext : model.extensionsUsed)
    if (!supported_extension(ext)) ignored += " " + ext;
  if (!ignored.empty()) warnings.push_back("extensions ignored:" + ignored);
  return {};
}

Result<GltfImportReport> import(const std::filesystem::path& path, ecs::World& world,
                                AssetStore& assets, ecs::Entity parent, ecs::Entity source,
                                bool activate_first_camera) {
  // 1-2. Read and parse.
  GltfImportReport report;
  ImageLoadState images;
  auto model = parse_file(path, images, report.warnings);
  if (!model) return model.error();

  Importer im{model.value(),
              path.string(),
              world,
              assets,
              source,
              activate_first_camera,
              std::move(report),
              std::move(images),
              {},
              {},
              {},
              {},
              false,
              {},
              {}};
  // 3. Extensions.
  KASKAD_TRY(check_extensions(im.model, im.file, im.report.warnings));
  // 4. Hierarchy.
  auto roots = root_nodes(im.model, im.file);
  if (!roots) return roots.error();

  // 5. Parents before children (depth-first, explicit stack: hierarchies can be deep).
  im.node_entities.assign(im.model.nodes.size(), ecs::kNullEntity);
  std::vector<std::pair<int, ecs::Entity>> stack;
  for (auto it = roots->rbegin(); it != roots->rend(); ++it) stack.emplace_back(*it, parent);
  while (!stack.empty()) {
    const auto [node, node_parent] = stack.back();
    stack.pop_back();
    auto entity = import_node(im, node, node_parent);
    if (!entity) return entity.error();
    const auto& children = im.model.nodes[std::size_t(node)].children;
    for (auto it = children.rbegin(); it != children.rend(); ++it)
      stack.emplace_back(*it, entity.value());
  }
  // 6. Skins and animations name nodes: every node has its entity now.
  KASKAD_TRY(import_skins_and_animations(im));
  return std::move(im.report);
}

}  // namespace

Result<GltfImportReport> import_gltf(const std::filesystem::path& path, ecs::World& world,
                                     AssetStore& assets, ecs::Entity parent, ecs::Entity source,
                                     bool activate_first_camera) {
  try {
    return import(path, world, assets, parent, source, activate_first_camera);
  } catch (const std::bad_alloc&) {
    return Error{path.string(), "", "out of memory while importing"};
  } catch (const std::exception& e) {
    return Error{path.string(), "", std::string("import failed: ") + e.what()};
  }
}

}  // namespace kaskad
