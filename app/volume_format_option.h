#pragma once
// --format: the file format of the posed volumes.
#include <string>

namespace repose {

/// ".nii.gz", "nrrd", ... -> the extension with its dot; UsageError for a format Repose does not write.
std::string normalizedFormat(std::string ext);

/// normalizedFormat, or ".seg.nrrd" (3D Slicer's segmentation): the formats of a label volume.
std::string normalizedLabelFormat(std::string ext);

/// The format of a posed image written beside labels in `labelsFormat`: the same, but a plain
/// ".nrrd" beside ".seg.nrrd" (a CT is no segmentation).
std::string imageFormatBeside(const std::string& labelsFormat);

/// --format vdb (OpenVDB grids instead of an image file).
bool isVdbFormat(const std::string& format);

}  // namespace repose
