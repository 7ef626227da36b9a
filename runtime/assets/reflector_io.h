// The "reflector" block of a scene entity (README "Reflection probes"): parse with validation
// and write back in canonical form. Used by scene_io.cpp only.
#pragma once

#include <nlohmann/json.hpp>

#include "components/reflector.h"
#include "runtime/core/json_reader.h"

namespace kaskad {

/// Reads every field `r` has; range errors and validate_reflector()'s rules name the key.
void read_reflector(json_reader::ObjectReader& r, Reflector& out);

/// Every field (the canonical form: `--set` can address each); "center" only when set.
nlohmann::json reflector_to_json(const Reflector& r);

}  // namespace kaskad
