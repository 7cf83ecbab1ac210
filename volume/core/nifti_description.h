#pragma once
// NIfTI-1's descrip field (80 bytes at offset 148: a note on what the file holds) written after the
// image library: ITK 5.2's NIfTI writer leaves it empty, whatever its metadata dictionary says.
#include <string>

namespace repose {

/// Sets descrip of the uncompressed NIfTI-1 file `nii` to `text` (cut to 79 bytes, zero-padded);
/// leaves any other file (a NIfTI-2 header) as it is.
/// With `gzipTo` non-empty, then compresses `nii` into `gzipTo` (gzip, zlib's default level, as the
/// NIfTI library writes .nii.gz) and removes `nii`. Throws WriteFailure naming `name` (the file as
/// the user knows it) when a write fails (a full disk, a size limit).
void describeNifti(const std::string& name, const std::string& nii, const std::string& text,
                   const std::string& gzipTo = "");

}  // namespace repose
