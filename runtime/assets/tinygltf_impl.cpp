// tinygltf's implementation, compiled once in its own translation unit (it is slow to compile).
// Configuration lives in tinygltf_config.h; see there why Draco is decoded by gltf_loader.cpp.
#define TINYGLTF_IMPLEMENTATION
#include "runtime/assets/tinygltf_config.h"
