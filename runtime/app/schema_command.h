// `kaskad schema`: the JSON Schemas of scene and material files and the settings reference,
// generated from the field tables (runtime/assets/scene_schema.h).
#pragma once

#include <filesystem>

namespace kaskad {

/// Writes docs/reference's generated files into `out_dir` (atomically, making the folder, one level), or
/// with `check` compares them with the files there and names each that differs or is missing.
/// Returns the exit status: 0 written or up to date, 1 an error or a stale file.
int run_schema_command(const std::filesystem::path& out_dir, bool check);

}  // namespace kaskad
