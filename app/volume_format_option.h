#pragma once
// --format: the file format of the posed volumes.
#include <string>

namespace repose {

/// ".nii.gz", "nrrd", ... -> the extension with its dot; UsageError for a format Repose does not write.
std::string normalizedFormat(std::string ext);

/// --format vdb (OpenVDB grids instead of an image file).
bool isVdbFormat(const std::string& format);

}  // namespace repose
