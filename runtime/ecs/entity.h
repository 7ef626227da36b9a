// Entity handles: a slot index plus a generation. Destroying an entity bumps its slot's generation,
// so an old handle to a reused slot is detected as stale instead of aliasing the new entity.
#pragma once

#include <cstdint>
#include <functional>

namespace kaskad::ecs {

struct Entity {
  static constexpr std::uint32_t kInvalidIndex = 0xffffffffu;

  std::uint32_t index = kInvalidIndex;
  std::uint32_t generation = 0;

  /// True for a handle that was ever created (it may still be stale: ask World::alive()).
  constexpr bool valid() const { return index != kInvalidIndex; }
  constexpr bool operator==(const Entity&) const = default;
};

/// The null handle: refers to no entity.
inline constexpr Entity kNullEntity{};

}  // namespace kaskad::ecs

template <>
struct std::hash<kaskad::ecs::Entity> {
  std::size_t operator()(const kaskad::ecs::Entity& e) const noexcept {
    return (std::size_t(e.generation) << 32) ^ e.index;
  }
};
