// glTF import, step 6: skins bound to their primitives and animations into clips (glTF 2.0,
// 3.7.3 "Skins" and 3.11 "Animations"). Runs after the node walk, since joints and channel
// targets name nodes anywhere in the file.
#include <algorithm>
#include <cmath>
#include <map>

#include "components/animation.h"
#include "runtime/assets/gltf_internal.h"

namespace kaskad::gltf_detail {
namespace {

/// Joints of one skin: far above real characters (a few hundred), and it bounds the joint
/// matrices a frame uploads per skinned draw.
constexpr std::size_t kMaxJoints = 1024;

/// glTF skin `index` as AssetStore::skins entry (inverse bind matrices; identity when absent).
Result<std::uint32_t> convert_skin(Importer& im, int index) {
  const tinygltf::Skin& g = im.model.skins[std::size_t(index)];
  const std::string where = label("skins", index, g.name);
  if (g.joints.empty()) return Error{im.file, where, "has no joints"};
  if (g.joints.size() > kMaxJoints)
    return Error{im.file, where, std::to_string(g.joints.size()) + " joints exceed the limit of " +
                                     std::to_string(kMaxJoints)};
  if (g.skeleton >= 0 && std::size_t(g.skeleton) >= im.model.nodes.size())
    return Error{im.file, where, "skeleton " + std::to_string(g.skeleton) + " out of range (" +
                                     std::to_string(im.model.nodes.size()) + " nodes)"};
  for (std::size_t j = 1; j < g.joints.size(); ++j)
    if (std::find(g.joints.begin(), g.joints.begin() + std::ptrdiff_t(j), g.joints[j]) !=
        g.joints.begin() + std::ptrdiff_t(j))
      return Error{im.file, where,
                   "joint node " + std::to_string(g.joints[j]) + " is listed twice (joints " +
                       "must be unique)"};
  SkinData skin;
  skin.name = g.name;
  skin.inverse_bind.assign(g.joints.size(), glm::mat4(1.0f));
  if (g.inverseBindMatrices >= 0) {
    auto m = read_float_accessor(im.model, im.file, g.inverseBindMatrices, 16,
                                 where + " inverseBindMatrices");
    if (!m) return m.error();
    if (m->size() < g.joints.size() * 16)
      return Error{im.file, where + " inverseBindMatrices",
                   std::to_string(m->size() / 16) + " matrices for " +
                       std::to_string(g.joints.size()) + " joints"};
    for (std::size_t j = 0; j < g.joints.size(); ++j)
      for (int c = 0; c < 16; ++c) {
        const float v = (*m)[j * 16 + std::size_t(c)];
        if (!std::isfinite(v))
          return Error{im.file, where + " inverseBindMatrices",
                       "matrix " + std::to_string(j) + " is not finite"};
        skin.inverse_bind[j][c / 4][c % 4] = v;
      }
    for (std::size_t j = 0; j < g.joints.size(); ++j)
      if (std::abs(glm::determinant(skin.inverse_bind[j])) < 1e-12f) {
        im.report.warnings.push_back(where + " inverseBindMatrices: matrix " + std::to_string(j) +
                                     " is singular (the vertices it moves collapse)");
        break;
      }
  }
  im.assets.skins.push_back(std::move(skin));
  return std::uint32_t(im.assets.skins.size() - 1);
}

Status bind_skins(Importer& im) {
  std::map<int, std::uint32_t> converted;  // glTF skin -> AssetStore::skins
  for (const Importer::SkinnedPrimitive& sp : im.skinned) {
    const tinygltf::Node& node = im.model.nodes[std::size_t(sp.node)];
    const std::string where = label("nodes", sp.node, node.name);
    if (std::size_t(node.skin) >= im.model.skins.size())
      return Error{im.file, where,
                   "skin " + std::to_string(node.skin) + " out of range (" +
                       std::to_string(im.model.skins.size()) + " skins)"};
    auto it = converted.find(node.skin);
    if (it == converted.end()) {
      auto skin = convert_skin(im, node.skin);
      if (!skin) return skin.error();
      it = converted.emplace(node.skin, skin.value()).first;
      ++im.report.skins;
    }
    const tinygltf::Skin& g = im.model.skins[std::size_t(node.skin)];
    Deformer d;
    d.skin = it->second;
    for (int j : g.joints) {
      if (j < 0 || std::size_t(j) >= im.node_entities.size())
        return Error{im.file, label("skins", node.skin, g.name),
                     "joint " + std::to_string(j) + " out of range (" +
                         std::to_string(im.node_entities.size()) + " nodes)"};
      if (!im.node_entities[std::size_t(j)].valid())
        return Error{im.file, label("skins", node.skin, g.name),
                     "joint node " + std::to_string(j) + " is not in the imported scene"};
      d.joints.push_back(im.node_entities[std::size_t(j)]);
    }
    const MeshData& mesh = im.assets.meshes[index(sp.mesh)];
    for (std::size_t k = 0; k < mesh.deform.joints.size(); ++k)
      if (mesh.deform.joints[k] >= d.joints.size() && mesh.deform.weights[k] > 0.0f)
        return Error{im.file, where,
                     "mesh '" + mesh.name + "' vertex " +
                         std::to_string(k / std::size_t(mesh.deform.influences)) + " names joint " +
                         std::to_string(mesh.deform.joints[k]) + " of a skin with " +
                         std::to_string(d.joints.size())};
    im.world.emplace<Deformer>(sp.entity, std::move(d));
  }
  return {};
}

Result<KeyInterpolation> interpolation_of(const Importer& im, const std::string& name,
                                          const std::string& where) {
  if (name.empty() || name == "LINEAR") return KeyInterpolation::linear;
  if (name == "STEP") return KeyInterpolation::step;
  if (name == "CUBICSPLINE") return KeyInterpolation::cubic_spline;
  return Error{im.file, where, "unknown interpolation '" + name + "' (LINEAR, STEP or CUBICSPLINE)"};
}

/// Channel `c` of animation `a`, or nullopt (with a warning) for one that cannot drive anything
/// here: a node outside the imported scene, an unknown path, weights of a node without targets.
Result<std::optional<AnimationClip::Channel>> read_channel(Importer& im, int a, int c) {
  const tinygltf::Animation& anim = im.model.animations[std::size_t(a)];
  const tinygltf::AnimationChannel& ch = anim.channels[std::size_t(c)];
  const std::string where = label("animations", a, anim.name) + " channels[" + std::to_string(c) + "]";
  using Skip = std::optional<AnimationClip::Channel>;
  if (ch.target_node < 0) {
    im.report.warnings.push_back(where + ": no target node; skipped");
    return Skip();
  }
  if (std::size_t(ch.target_node) >= im.node_entities.size())
    return Error{im.file, where,
                 "target node " + std::to_string(ch.target_node) + " out of range (" +
                     std::to_string(im.node_entities.size()) + " nodes)"};
  const ecs::Entity target = im.node_entities[std::size_t(ch.target_node)];
  if (!target.valid()) {
    im.report.warnings.push_back(where + ": drives a node outside the imported scene; skipped");
    return Skip();
  }
  AnimationClip::Channel out;
  out.node = std::uint32_t(ch.target_node);
  int components = 3;
  std::size_t tracks = 1;
  if (ch.target_path == "translation") {
    out.path = AnimatedPath::translation;
  } else if (ch.target_path == "rotation") {
    out.path = AnimatedPath::rotation;
    components = 4;
  } else if (ch.target_path == "scale") {
    out.path = AnimatedPath::scale;
  } else if (ch.target_path == "weights") {
    out.path = AnimatedPath::weights;
    components = 1;
    const auto* w = im.world.try_get<MorphWeights>(target);
    if (w == nullptr) {
      im.report.warnings.push_back(where + ": animates weights of a node without morph targets; skipped");
      return Skip();
    }
    tracks = w->weights.size();
  } else {
    im.report.warnings.push_back(where + ": path '" + ch.target_path + "' is not animated here; skipped");
    return Skip();
  }
  if (ch.sampler < 0 || std::size_t(ch.sampler) >= anim.samplers.size())
    return Error{im.file, where,
                 "sampler " + std::to_string(ch.sampler) + " out of range (" +
                     std::to_string(anim.samplers.size()) + " samplers)"};
  const tinygltf::AnimationSampler& s = anim.samplers[std::size_t(ch.sampler)];
  const std::string swhere = label("animations", a, anim.name) + " samplers[" + std::to_string(ch.sampler) + "]";
  auto interpolation = interpolation_of(im, s.interpolation, swhere);
  if (!interpolation) return interpolation.error();
  auto times = read_float_accessor(im.model, im.file, s.input, 1, swhere + " input");
  if (!times) return times.error();
  auto values = read_float_accessor(im.model, im.file, s.output, components, swhere + " output");
  if (!values) return values.error();
  const std::size_t keys = times->size();
  const std::size_t per_key = *interpolation == KeyInterpolation::cubic_spline ? 3 : 1;
  const std::size_t elements = values->size() / std::size_t(components);
  if (elements != keys * per_key * tracks)
    return Error{im.file, swhere,
                 std::to_string(elements) + " output values for " + std::to_string(keys) +
                     " keys (" + std::to_string(keys * per_key * tracks) + " expected)"};
  for (std::size_t t = 0; t < tracks; ++t) {
    KeyTrack track;
    track.interpolation = *interpolation;
    track.kind = out.path == AnimatedPath::rotation ? KeyKind::rotation : KeyKind::vector;
    track.times = *times;
    track.values.resize(keys * per_key, glm::vec4(0.0f));
    // Weights: each element holds every target's value in turn (glTF 3.11).
    for (std::size_t e = 0; e < keys * per_key; ++e)
      for (int k = 0; k < components; ++k)
        track.values[e][k] = (*values)[(e * tracks + t) * std::size_t(components) + std::size_t(k)];
    if (const std::string bad = validate_track(track); !bad.empty())
      return Error{im.file, swhere, bad};
    out.tracks.push_back(std::move(track));
  }
  return std::optional<AnimationClip::Channel>(std::move(out));
}

Status import_animations(Importer& im) {
  const std::uint32_t first = std::uint32_t(im.assets.animations.size());
  for (std::size_t a = 0; a < im.model.animations.size(); ++a) {
    const tinygltf::Animation& anim = im.model.animations[a];
    AnimationClip clip;
    clip.name = anim.name.empty() ? std::string("animation_").append(std::to_string(a)) : anim.name;
    // Scenes and --set name clips: a name the file repeats gets its index.
    for (std::size_t b = 0; b < a; ++b)
      if (im.assets.animations[first + b].name == clip.name) {
        // Appended piecewise: `s += "_" + x` trips GCC 12's false -Wrestrict (PR 105651).
        clip.name += '_';
        clip.name += std::to_string(a);
        break;
      }
    for (std::size_t c = 0; c < anim.channels.size(); ++c) {
      auto channel = read_channel(im, int(a), int(c));
      if (!channel) return channel.error();
      if (!channel->has_value()) continue;
      for (const KeyTrack& t : (*channel)->tracks) clip.duration = std::max(clip.duration, t.end());
      clip.channels.push_back(std::move(**channel));
    }
    im.assets.animations.push_back(std::move(clip));
    ++im.report.animations;
  }
  if (im.model.animations.empty() || !im.source.valid()) return {};
  Animator animator;
  animator.first_clip = first;
  animator.clips.resize(im.model.animations.size());
  for (std::size_t k = 0; k < animator.clips.size(); ++k)
    animator.names.push_back(im.assets.animations[first + k].name);
  animator.clips[0].playing = true;  // a model plays its first clip unless the scene says not
  animator.cues.resize(animator.clips.size());
  animator.nodes = im.node_entities;
  im.world.emplace<Animator>(im.source, std::move(animator));
  return {};
}

}  // namespace

Status import_skins_and_animations(Importer& im) {
  KASKAD_TRY(bind_skins(im));
  return import_animations(im);
}

}  // namespace kaskad::gltf_detail
