// One run's outputs must each name their own file, and none may name one of its inputs: the
// later write would replace the earlier output, or the input the run read.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "runtime/result/result.h"

namespace kaskad {

/// A file a run reads or writes, with the option or argument that names it (for messages).
struct NamedPath {
  std::string option;  ///< "-o", "--sphere", "IN", ...
  std::filesystem::path path;
};

/// Refuses two outputs naming one file and an output naming an input (paths compared after
/// std::filesystem::weakly_canonical: "a/../b.png" and "b.png" are one file). The error names
/// the file and both options.
inline Status check_distinct_outputs(const std::vector<NamedPath>& outputs,
                                     const std::vector<NamedPath>& inputs = {}) {
  std::error_code ec;
  auto same = [&](const NamedPath& a, const NamedPath& b) {
    return std::filesystem::weakly_canonical(a.path, ec) ==
           std::filesystem::weakly_canonical(b.path, ec);
  };
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    for (const NamedPath& in : inputs)
      if (same(outputs[i], in))
        return Error{outputs[i].path.string(), "",
                     outputs[i].option + " names the file " + in.option +
                         " reads: writing it would replace the input"};
    for (std::size_t j = 0; j < i; ++j)
      if (same(outputs[i], outputs[j]))
        return Error{outputs[i].path.string(), "",
                     outputs[j].option + " and " + outputs[i].option +
                         " name the same file: one would replace the other"};
  }
  return {};
}

}  // namespace kaskad
