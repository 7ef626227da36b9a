// Material files (JSON, content/materials/): features, typed parameters and textures, validated
// against the feature manifest (content/shaders/features.json). Format in README.md ("Materials").
#pragma once

#include <filesystem>

#include "components/material.h"
#include "runtime/assets/asset_store.h"
#include "runtime/core/result.h"
#include "runtime/render/feature_manifest.h"

namespace kaskad {

/// Reads a material file; textures (paths relative to the file) are loaded into `assets` through
/// OpenImageIO. Errors name the file and key: unknown feature or parameter, wrong type, value out
/// of range, contradictory features (excludes / requires), a parameter or texture whose feature is
/// not listed, a listed texture feature without its texture, unreadable texture images.
Result<Material> load_material_file(const std::filesystem::path& file,
                                    const render::FeatureManifest& manifest, AssetStore& assets);

}  // namespace kaskad
