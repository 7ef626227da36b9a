// Built-in unit primitives (see components/model.h for sizes and orientation).
#pragma once

#include "components/model.h"
#include "runtime/assets/asset_store.h"

namespace kaskad {

/// Triangle mesh of a unit primitive with outward normals, uvs and counter-clockwise front faces.
/// Precondition: segments in [3, 1024].
MeshData make_primitive(PrimitiveShape shape, int segments);

/// One tile of the terrain primitive split into tiles x tiles meshes (so that culling can keep
/// parts of it): the cells [tile_x * n, (tile_x + 1) * n) x [tile_z * n, ...) of the whole
/// `segments` x `segments` grid, n = segments / tiles, in the whole terrain's local space.
/// Edge vertices equal the neighbours' bit for bit. Precondition: segments % tiles == 0,
/// 0 <= tile_x, tile_z < tiles.
MeshData make_terrain_tile(int segments, int tiles, int tile_x, int tile_z);

}  // namespace kaskad
