// The feature manifest: the shader features of kFeatureTable (runtime/features/variant_key.h, the
// one place they are declared) as runtime values, plus the typed material parameters and textures
// of content/shaders/features.json, with defaults, ranges and the feature each one belongs to.
// The manifest turns a VariantKey into defines (the one function that produces both MATERIAL_*
// and VARIANT_* defines) and checks material files against the declared parameters.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "runtime/result/result.h"
#include "runtime/features/variant_key.h"

namespace kaskad::render {

/// A row of kFeatureTable with owned strings.
struct Feature {
  std::string name;
  FeatureKind kind = FeatureKind::material;
  std::string define;
  std::uint8_t stages = 0;               ///< ShaderStage bits
  std::vector<std::string> requires_;    ///< features that must be on when this one is
  std::vector<std::string> excludes;     ///< features that must be off when this one is
  std::vector<std::string> values;       ///< enumerated feature: value names (index = value)
  int min = 0, max = 1;                  ///< integer range of the value (switch: 0..1)
  VariantKey::Field field{0, 0};         ///< where the value lives in the key
  int key_bias = 0;                      ///< stored = value - key_bias (= min)
};

enum class ParamType { float_, vec2, vec3, vec4, bool_ };

struct MaterialParameter {
  std::string name;
  ParamType type = ParamType::float_;
  std::vector<double> default_value;  ///< 1, 2, 3 or 4 numbers (bool: 0 or 1)
  double min = 0, max = 1;
  std::string feature;  ///< only allowed when this feature is on (empty: always)
};

struct MaterialTextureSlot {
  std::string name;
  std::string feature;  ///< the feature this texture turns on
  bool srgb = true;
};

class FeatureManifest {
 public:
  /// Reads and validates the parameters and textures of a manifest. Errors name the file and
  /// JSON path: unknown keys, unknown feature references, a "features" section (features are
  /// declared in kFeatureTable, not in the file).
  static Result<FeatureManifest> load(const std::filesystem::path& file);

  /// The features of kFeatureTable, no parameters or textures.
  FeatureManifest();

  const std::vector<Feature>& features() const { return features_; }
  const std::vector<MaterialParameter>& parameters() const { return parameters_; }
  const std::vector<MaterialTextureSlot>& textures() const { return textures_; }
  const Feature* find(const std::string& name) const;
  const MaterialParameter* find_parameter(const std::string& name) const;
  const MaterialTextureSlot* find_texture(const std::string& name) const;

  /// A feature's value in a key (enumerated: the index; cascade_count: the count).
  int value(const Feature& f, VariantKey key) const;
  /// Sets a feature's value; precondition: in [f.min, f.max].
  VariantKey with(VariantKey key, const Feature& f, int value) const;

  /// Empty when the key satisfies every requires/excludes rule and range, else the first broken
  /// rule in words ("reflection_cube excludes reflection_sphere").
  std::string check(VariantKey key) const;

  /// One `#define NAME VALUE` pair per feature for `stage` (every feature is always defined, so
  /// shaders use `#if`), plus NAME_VALUENAME constants for enumerated features, plus BIT_NAME =
  /// the key bit of every material feature (features.glsl's ENABLED() reads them).
  std::vector<std::pair<std::string, std::string>> defines(VariantKey key, ShaderStage stage) const;

  /// "normal_map shadow shadow_filter=pcf3x3 cascade_count=4": the features that are on.
  std::string describe(VariantKey key) const;

 private:
  std::vector<Feature> features_;
  std::vector<MaterialParameter> parameters_;
  std::vector<MaterialTextureSlot> textures_;
};

}  // namespace kaskad::render
