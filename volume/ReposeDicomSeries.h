#ifndef ReposeDicomSeries_h
#define ReposeDicomSeries_h
// DICOM CT series in and out through ITK's GDCM image IO: the geometry checked slice by slice
// (dicom_slice_stack.h), rescale slope and intercept applied (voxels in Hounsfield units), and the
// patient and study carried from an input series to a derived one.
#include "itkImage.h"

#include <string>
#include <utility>
#include <vector>

class vtkImageData;

namespace repose
{

/// DICOM attributes as "gggg|eeee" keys (ITK's spelling) and their text values.
using DicomTags = std::vector<std::pair<std::string, std::string>>;

/// The attributes an image carries in its field data ("DicomTags": "gggg|eeee=value" strings, as
/// vtkReposeImageReader fills them from a DICOM series); empty when it has none.
DicomTags DicomTagsOf(vtkImageData* image);

struct DicomSeriesVolume
{
  itk::Image<float, 3>::Pointer Image; ///< voxels after rescale (HU for CT), ITK's LPS geometry
  std::string SeriesUID;
  DicomTags PatientAndStudy; ///< of the first slice: who and which study, to carry to derived series
};

/// Reads the series seriesUID (empty: the only one) of the DICOM files in folder (not its
/// subfolders). Throws std::runtime_error with a one-line reason: no series, several and none
/// chosen (they are listed with their descriptions and slice counts), an unknown UID, slices that
/// make no regular grid (gantry tilt, a missing slice, mixed orientations), unreadable pixels.
DicomSeriesVolume ReadDicomSeries(const std::string& folder, const std::string& seriesUID);

/// Writes a CT volume (HU, rounded to 16-bit signed integers, clamped) into folder, which must not
/// exist, as a DICOM CT series of one file per slice, IM00001.dcm ...: new Series and SOP Instance
/// UIDs, image type DERIVED\SECONDARY, the given series description, and the patient and study of
/// `carried` (a new study and an anonymous patient when empty). Slices are in the image's k order,
/// positioned by its origin, spacing and direction. Throws std::runtime_error on failure; the
/// folder is then removed.
void WriteDicomSeries(const itk::Image<float, 3>* image, const std::string& folder, const DicomTags& carried,
  const std::string& description);

} // namespace repose

#endif
