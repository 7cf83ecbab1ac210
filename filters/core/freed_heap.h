#pragma once
// Freed heap memory given back to the system between preprocessing stages.

namespace repose {

/// Returns the pages of freed heap blocks to the system (glibc's malloc_trim; nothing elsewhere).
/// free() keeps them resident: TetGen's mesh is freed as thousands of pool blocks in the middle of
/// the heap, and without this the weights' matrices came on top of it (medium phantom: the weights
/// stage 1155 MiB resident with a few hundred MiB of it live).
void releaseFreedHeap();

}  // namespace repose
