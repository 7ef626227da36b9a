#pragma once

#include <string>

namespace kaskad {

/// Human-readable entity name; unique names make `--set NAME.component.field=value` unambiguous.
struct Name {
  std::string value;
};

}  // namespace kaskad
