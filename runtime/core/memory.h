// Process-wide memory policy for a real-time frame loop.
#pragma once

namespace kaskad {

/// Keeps the memory the process frees for its own reuse instead of handing it back to the kernel
/// (glibc: blocks up to 32 MiB come from the heap, and the heap is trimmed only past 256 MiB of
/// free space at its top). A frame allocates and frees the same large blocks every frame (its
/// draws and instance records, llvmpipe's bins and vertex buffers); by default glibc gives such
/// pages back and the next frame faults them in again, zeroed: 1,300 page faults a frame on
/// scaling_bench's 10,000-instance field, 225 with this policy. The price is a resident size
/// that stays at its peak. It replaces glibc's dynamic thresholds and any MALLOC_*_ settings
/// from the environment. Call once, first thing in main(); elsewhere than glibc (and where
/// glibc refuses a value, as a 32-bit one refuses 32 MiB) it leaves the defaults.
void keep_freed_memory();

}  // namespace kaskad
