#ifndef ReposeDicomSegmentation_h
#define ReposeDicomSegmentation_h
// Label volumes as DICOM Segmentation objects (DCMTK's dcmseg): one binary segment per label, with
// its name and recommended display colour, frames positioned in the patient frame so that any
// DICOM viewer overlays them on the CT they were made with.
#include "ReposeDicomSeries.h"

#include <array>
#include <string>
#include <vector>

class vtkImageData;

namespace repose
{

struct DicomSegment
{
  int Value = 0;                           ///< the label value in the volume
  std::string Name;                        ///< SegmentLabel (at most 64 characters kept)
  std::array<double, 3> Colour{ 1, 1, 1 }; ///< sRGB in [0, 1]
  bool Bone = false;                       ///< segmented property type: bone, else tissue
};

/// A label grid: dims (i fastest), first voxel's centre, spacing (mm) and direction (LPS, columns
/// are the i, j, k axes, row-major 3x3), and one label value per voxel.
struct LabelGrid
{
  std::array<int, 3> Dims{};
  std::array<double, 3> Origin{}, Spacing{};
  std::array<double, 9> Direction{ 1, 0, 0, 0, 1, 0, 0, 0, 1 };
  std::vector<int> Values;
};

/// The grid of a vtkImageData (its extent's first voxel as the origin), with its scalars as
/// labels when withValues (rounded to int).
LabelGrid LabelGridOf(vtkImageData* image, bool withValues);

/// Writes `segments` of `labels` (labels not listed, and empty ones, are left out; a segment's
/// frames are its slices that hold it) to `path` as a binary DICOM Segmentation. Patient, study and
/// frame of reference come from `carried` (new ones when absent): with a CT's, viewers overlay the
/// segmentation on it. Throws std::runtime_error with DCMTK's reason.
void WriteDicomSegmentation(const LabelGrid& labels, const std::vector<DicomSegment>& segments,
  const std::string& path, const DicomTags& carried, const std::string& description);

/// Reads a binary DICOM Segmentation back onto `grid`'s lattice (its Values are overwritten: each
/// voxel the label value of the last segment covering it, 0 elsewhere; segment values come from
/// `segments` by name, else the segment number). Frames off the grid's planes are an error.
/// Returns the segment names in segment-number order.
std::vector<std::string> ReadDicomSegmentation(
  const std::string& path, const std::vector<DicomSegment>& segments, LabelGrid& grid);

} // namespace repose

#endif
