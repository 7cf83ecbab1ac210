#pragma once
// What a mesh file says about itself, checked before a reader believes it: VTK's readers allocate
// by a header's counts (a PLY claiming 10^9 vertices ends in std::bad_alloc), read random bytes as
// an empty STL, drop OBJ faces with bad indices without a word and take a truncated binary STL.
#include <string>

namespace repose {

/// Checks the file at `path` (format from its extension: .stl, .ply, .obj, .vtk, .vtp, .vtu) before
/// it is read: every count its header claims fits in the file's size (deflate expands at most
/// 1032 times), a binary STL is exactly 84 + 50 x triangles bytes and an ASCII one ends with
/// `endsolid`, OBJ vertices are finite and every face index names a vertex of the file.
/// Throws std::runtime_error with a short reason (no file name).
void checkMeshFileClaims(const std::string& path);

}  // namespace repose
