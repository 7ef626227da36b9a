// Helpers shared by the glTF loader tests (gltf_loader_test.cpp: real content, nodes and errors;
// gltf_animation_test.cpp: skins, morph targets and clips; gltf_materials_test.cpp: materials,
// uv sets and texture formats): importing a file, small glTF documents written by the tests, and
// what every import must satisfy.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "components/animation.h"
#include "components/camera.h"
#include "components/light.h"
#include "components/material.h"
#include "components/mesh_renderer.h"
#include "components/model.h"
#include "components/name.h"
#include "components/shadow_settings.h"
#include "components/transform.h"
#include "runtime/assets/gltf_loader.h"
#include "runtime/assets/image_io.h"
#include "runtime/features/variant_key.h"
#include "tests/unit/assets/asset_test_util.h"

namespace kaskad::gltf_test {

using nlohmann::json;
using test::base64;
using test::content_path;
using test::read_bytes;
using test::temp_dir;
using test::write_bytes;
using test::write_text;

inline constexpr float kPi = std::numbers::pi_v<float>;

/// A world, an asset store and the result of importing one file into them.
struct Imported3d {
  ecs::World world;
  AssetStore assets;
  ecs::Entity root;
  Result<GltfImportReport> report = Error{};
};

inline std::unique_ptr<Imported3d> import_file(const std::filesystem::path& path,
                                        bool activate_first_camera = false) {
  auto s = std::make_unique<Imported3d>();
  s->root = s->world.create();
  s->report = import_gltf(path, s->world, s->assets, s->root, s->root, activate_first_camera);
  return s;
}

inline bool mentions(const Error& error, const std::string& text) {
  return error.to_string().find(text) != std::string::npos;
}

inline bool warns(const GltfImportReport& report, const std::string& text) {
  for (const auto& w : report.warnings)
    if (w.find(text) != std::string::npos) return true;
  return false;
}

/// Every entity with a Name, by name (names are unique in the files used here).
inline std::map<std::string, ecs::Entity> entities_by_name(ecs::World& world) {
  std::map<std::string, ecs::Entity> out;
  world.view<Name, Transform>().each(
      [&](ecs::Entity e, Name& name, Transform&) { out[name.value] = e; });
  return out;
}

/// Invariants every imported mesh must satisfy, whatever the file.
inline void expect_valid_meshes(const AssetStore& assets) {
  for (const MeshData& m : assets.meshes) {
    SCOPED_TRACE(m.name);
    ASSERT_FALSE(m.positions.empty());
    ASSERT_EQ(m.normals.size(), m.positions.size());
    ASSERT_TRUE(m.uvs.empty() || m.uvs.size() == m.positions.size());
    ASSERT_TRUE(m.tangents.empty() || m.tangents.size() == m.positions.size());
    ASSERT_EQ(m.indices.size() % 3, 0u);
    for (std::uint32_t i : m.indices) ASSERT_LT(i, m.positions.size());
    ASSERT_FALSE(m.bounds.empty());
    for (const glm::vec3& p : m.positions) {
      ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
      for (int a = 0; a < 3; ++a) {
        ASSERT_GE(p[a], m.bounds.min[a]);
        ASSERT_LE(p[a], m.bounds.max[a]);
      }
    }
    for (const glm::vec3& n : m.normals) {
      const float len = glm::length(n);
      ASSERT_TRUE(len == 0.0f || std::abs(len - 1.0f) < 1e-4f) << len;
    }
  }
}

template <class T>
inline void append(std::vector<std::uint8_t>& bytes, std::initializer_list<T> values) {
  for (T v : values) {
    std::uint8_t b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    bytes.insert(bytes.end(), b, b + sizeof(T));
  }
}

/// A small valid glTF (JSON with a base64 buffer): one triangle without normals, indexed by
/// u16 indices, under a node with TRS; tests modify the returned document to break it.
/// Buffer: bytes 0-35 positions (3 x vec3 float), 36-41 indices (3 x u16), 42-43 padding.
inline json triangle_gltf() {
  std::vector<std::uint8_t> buffer;
  append<float>(buffer, {0, 0, 0, 1, 0, 0, 0, 1, 0});
  append<std::uint16_t>(buffer, {0, 1, 2, 0});
  json doc = {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes",
       {{{"name", "parent"},
         {"translation", {1, 2, 3}},
         {"rotation", {0, 0.70710678, 0, 0.70710678}},
         {"scale", {2, 2, 2}},
         {"children", {1}}},
        {{"name", "tri"}, {"mesh", 0}}}},
      {"meshes",
       {{{"name", "triangle"},
         {"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
        {{"bufferView", 1}, {"componentType", 5123}, {"count", 3}, {"type", "SCALAR"}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}},
        {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 6}}}},
      {"buffers",
       {{{"byteLength", buffer.size()},
         {"uri", "data:application/octet-stream;base64," + base64(buffer)}}}},
  };
  return doc;
}

inline std::filesystem::path write_gltf(const std::string& name, const json& doc) {
  const auto path = temp_dir() / name;
  write_text(path, doc.dump(2));
  return path;
}

inline void expect_import_error(const std::filesystem::path& path, const std::string& also_mentions = {}) {
  auto s = import_file(path);
  ASSERT_FALSE(s->report.ok()) << path;
  const std::string text = s->report.error().to_string();
  EXPECT_TRUE(mentions(s->report.error(), path.string())) << text;
  if (!also_mentions.empty()) {
    EXPECT_TRUE(mentions(s->report.error(), also_mentions)) << text;
  }
}

/// triangle_gltf() with two 2x2 PNG images (written next to the file), one texture each, and
/// material 0 on the triangle set to `material`.
inline json textured_triangle(const json& material) {
  for (const char* name : {"tex_a.png", "tex_b.png"}) {
    Image image;
    image.width = image.height = 2;
    image.channels = 4;
    image.pixels.assign(16, 0.5f);
    EXPECT_TRUE(save_image(temp_dir() / name, image).ok());
  }
  json doc = triangle_gltf();
  doc["images"] = {{{"uri", "tex_a.png"}}, {{"uri", "tex_b.png"}}};
  doc["textures"] = {{{"source", 0}}, {{"source", 1}}};
  doc["materials"] = {material};
  doc["meshes"][0]["primitives"][0]["material"] = 0;
  return doc;
}

/// The one Material of an import (the triangle's).
inline Material only_material(Imported3d& s) {
  Material out;
  int n = 0;
  s.world.view<Material>().each([&](ecs::Entity, Material& m) { out = m, ++n; });
  EXPECT_EQ(n, 1);
  return out;
}

}  // namespace kaskad::gltf_test
