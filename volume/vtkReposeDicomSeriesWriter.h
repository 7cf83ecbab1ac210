#ifndef vtkReposeDicomSeriesWriter_h
#define vtkReposeDicomSeriesWriter_h
// Writes a 3-D CT volume (Hounsfield units, any scalar type) as a DICOM CT series: one file per
// slice in the folder FileName (which must not exist), 16-bit signed voxels, a new Series Instance
// UID and SOP Instance UIDs, image type DERIVED\SECONDARY and SeriesDescription. The patient and
// study travel from the input's field data "DicomTags" (as vtkReposeImageReader fills it from a
// DICOM input); without them the series gets a new study and an anonymous patient. The series is
// written into a temporary sibling folder and renamed into place, so a failed write leaves nothing.

#include "ReposeVolumeModule.h"
#include "vtkReposeWriterBase.h"

#include <string>

class vtkImageData;

class REPOSEVOLUME_EXPORT vtkReposeDicomSeriesWriter : public vtkReposeWriterBase
{
public:
  static vtkReposeDicomSeriesWriter* New();
  vtkTypeMacro(vtkReposeDicomSeriesWriter, vtkReposeWriterBase);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// DICOM SeriesDescription (at most 64 characters are kept), e.g. how the volume was derived.
  vtkSetStringMacro(SeriesDescription);
  vtkGetStringMacro(SeriesDescription);

  /// Gives an image that has none (no "DicomTags" in its field data) a new study, frame of reference
  /// and an anonymous patient, so that the series and segmentations written from it and from images
  /// given the same tags belong together. An image that has them is left as it is.
  static void AssignNewStudy(vtkImageData* image);

protected:
  vtkReposeDicomSeriesWriter();
  ~vtkReposeDicomSeriesWriter() override;

  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  char* SeriesDescription = nullptr;

private:
  vtkReposeDicomSeriesWriter(const vtkReposeDicomSeriesWriter&) = delete;
  void operator=(const vtkReposeDicomSeriesWriter&) = delete;
};

#endif
