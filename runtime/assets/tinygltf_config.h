// Private to runtime/assets: the one place that configures and includes tinygltf 2.7, so that
// tinygltf_impl.cpp (which compiles its implementation) and gltf_loader.cpp see identical
// declarations (the TINYGLTF_* switches change the TinyGLTF class; differing ones break the ODR).
//
// - No stb_image / stb_image_write: images are decoded through OpenImageIO by the loader's
//   image callback (TinyGLTF::SetImageLoader), and we never write glTF.
// - No TINYGLTF_ENABLE_DRACO, deliberately: tinygltf 2.7's Draco path (ParseDracoExtension)
//   indexes bufferViews, buffers and accessors without range checks, ignores decode failures
//   (the primitive silently keeps accessors without data), dereferences a null attribute when a
//   Draco stream lacks a declared attribute id, and converts values into a 4-element stack array
//   with the stream's component count. Corrupt files could crash it, so gltf_loader.cpp decodes
//   KHR_draco_mesh_compression itself with libdraco, validating every index (see decode_draco).
//   Without Draco support tinygltf refuses index accessors that have no buffer view, as Draco
//   primitives' do, so the loader drops those from the JSON first (see strip_draco_indices).
// - JSON through nlohmann/json (tinygltf's default; Debian's nlohmann-json3-dev).
#pragma once

#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE

#include <tiny_gltf.h>
