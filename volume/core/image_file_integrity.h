#pragma once
// Integrity of an image file before its voxels are read: a file cut short, a header promising more
// slices than the file holds, or a damaged gzip/zlib stream must be refused, not zero-filled.
#include <cstdint>
#include <string>

namespace repose {

/// Checks the geometry fields of an image header before an image library parses them: NIfTI voxel
/// sizes positive and finite, qform/sform finite; NRRD and MetaImage spacings, origins and
/// directions finite. Reads only the header. Throws std::runtime_error with a short reason.
void checkImageHeader(const std::string& path);

/// Checks that the file at `path` holds all `voxelBytes` bytes of voxels its header promises
/// (dims × bytes per voxel, from the header) and that every gzip or zlib stream in it is whole:
/// read to its end, CRC/Adler and length trailers verified. Knows NIfTI-1/2 (.nii, .nii.gz), NRRD
/// (attached or detached, raw or gzip) and MetaImage (.mha/.mhd, raw or zlib); for NIfTI it also
/// refuses float voxels that are NaN or infinite (the NIfTI library silently turns them into 0).
/// Other layouts are accepted as they are.
/// Reads the file as a stream: memory does not grow with the file. Throws std::runtime_error with
/// a short reason (no file name).
void checkImageFileIntegrity(const std::string& path, std::uint64_t voxelBytes);

}  // namespace repose
