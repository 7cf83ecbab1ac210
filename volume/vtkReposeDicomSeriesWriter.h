#ifndef vtkReposeDicomSeriesWriter_h
#define vtkReposeDicomSeriesWriter_h
// Writes a 3-D CT volume (Hounsfield units, any scalar type) as a DICOM CT series: one file per
// slice in the folder FileName (which must not exist), 16-bit signed voxels, a new Series Instance
// UID and SOP Instance UIDs, image type DERIVED\SECONDARY and SeriesDescription. The patient and
// study travel from the input's field data "DicomTags" (as vtkReposeImageReader fills it from a
// DICOM input); without them the series gets a new study and an anonymous patient. The series is
// written into a temporary sibling folder and renamed into place, so a failed write leaves nothing.

#include "ReposeVolumeModule.h"
#include "vtkImageAlgorithm.h"

#include <string>

class REPOSEVOLUME_EXPORT vtkReposeDicomSeriesWriter : public vtkImageAlgorithm
{
public:
  static vtkReposeDicomSeriesWriter* New();
  vtkTypeMacro(vtkReposeDicomSeriesWriter, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// The series' folder.
  vtkSetStringMacro(FileName);
  vtkGetStringMacro(FileName);

  /// DICOM SeriesDescription (at most 64 characters are kept), e.g. how the volume was derived.
  vtkSetStringMacro(SeriesDescription);
  vtkGetStringMacro(SeriesDescription);

  /// Updates the input and writes it. Returns 1 on success, 0 on failure (see GetLastError()).
  int Write();

  /// One-line description of the last failure ("FOLDER: cannot write (reason)"), empty after success.
  const char* GetLastError() { return this->LastError.c_str(); }

protected:
  vtkReposeDicomSeriesWriter();
  ~vtkReposeDicomSeriesWriter() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int FillOutputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  char* FileName = nullptr;
  char* SeriesDescription = nullptr;
  std::string LastError;

private:
  vtkReposeDicomSeriesWriter(const vtkReposeDicomSeriesWriter&) = delete;
  void operator=(const vtkReposeDicomSeriesWriter&) = delete;
};

#endif
