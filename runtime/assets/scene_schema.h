// JSON Schemas of Kaskad's files (draft 2020-12), generated from the field tables
// (runtime/fields/fields.h) and, for material files, the feature manifest: `kaskad schema`
// writes them with the settings reference (docs/reference/), a test checks the committed copies
// against what this code produces and validates every file under content/ with them. The
// structure around the tables (entities, transforms, model node blocks, a reflector's box) is
// written here, once, as the readers in scene_io.cpp and reflector_io.cpp take it.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "runtime/features/feature_manifest.h"

namespace kaskad {

/// The schema of scene files (content/scenes/*.json).
nlohmann::json scene_schema();

/// The schema of material files (content/materials/*.json): features, parameters and texture
/// slots as `manifest` declares them.
nlohmann::json material_schema(const render::FeatureManifest& manifest);

/// The settings reference (Markdown): one table per scene block, from the field tables.
std::string settings_reference();

/// The files of docs/reference/ as `kaskad schema` writes them: {file name, contents}.
std::vector<std::pair<std::string, std::string>> reference_files(
    const render::FeatureManifest& manifest);

}  // namespace kaskad
