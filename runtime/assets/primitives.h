// Built-in unit primitives (see components/model.h for sizes and orientation).
#pragma once

#include "components/model.h"
#include "runtime/assets/asset_store.h"

namespace kaskad {

/// Triangle mesh of a unit primitive with outward normals, uvs and counter-clockwise front faces.
/// Precondition: segments in [3, 1024].
MeshData make_primitive(PrimitiveShape shape, int segments);

}  // namespace kaskad
