// The "reflector" block of a scene entity (docs/guide/scenes.md, "Reflectors"): parse with
// validation and write back in canonical form. Used by scene_io.cpp only.
#pragma once

#include <nlohmann/json.hpp>

#include "components/reflector.h"
#include "runtime/assets/env_map.h"
#include "runtime/core/json_reader.h"

namespace kaskad {

/// Reads every field `r` has; range errors and validate_reflector()'s rules name the key.
void read_reflector(json_reader::ObjectReader& r, Reflector& out);

/// Every field (the canonical form: `--set` can address each); "center" only when set.
nlohmann::json reflector_to_json(const Reflector& r);

/// Loads a static_file Reflector's cube map with its layout and 3ds Max option (env_map.h).
Result<CubeMap> load_static_env_map(const std::filesystem::path& file, const Reflector& r);

}  // namespace kaskad
