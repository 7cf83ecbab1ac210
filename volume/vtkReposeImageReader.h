#ifndef vtkReposeImageReader_h
#define vtkReposeImageReader_h
// Reads a 3-D scalar image through ITK (NIfTI .nii/.nii.gz, NRRD .nrrd/.nhdr, MetaImage .mha/.mhd)
// into vtkImageData with the file's origin, spacing and direction matrix (ITK's LPS frame).
// Integer pixels become VTK_INT, floating-point pixels VTK_FLOAT; the scalars are named "ImageScalars".
// A folder is read as a DICOM series (ITK's GDCM IO): the one it holds, or SeriesUID; its slices must
// make a regular grid (oblique is fine; gantry tilt, a missing slice or mixed orientations are
// refused); rescale slope and intercept are applied (VTK_FLOAT, Hounsfield units for CT). The first
// slice's patient and study attributes travel in the output's field data ("DicomTags": "gggg|eeee=value"
// strings), so a derived series can keep them (vtkReposeDicomSeriesWriter).

#include "ReposeVolumeModule.h"
#include "vtkImageAlgorithm.h"
#include "vtkSmartPointer.h"

#include <string>

class vtkImageData;

class REPOSEVOLUME_EXPORT vtkReposeImageReader : public vtkImageAlgorithm
{
public:
  static vtkReposeImageReader* New();
  vtkTypeMacro(vtkReposeImageReader, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  vtkSetStringMacro(FileName);
  vtkGetStringMacro(FileName);

  /// DICOM folders: the Series Instance UID to read when the folder holds several (empty: the only one).
  vtkSetStringMacro(SeriesUID);
  vtkGetStringMacro(SeriesUID);

  /// One-line description of the last failure ("FILE: cannot read (reason)"), empty after success.
  const char* GetLastError() { return this->LastError.c_str(); }

protected:
  vtkReposeImageReader();
  ~vtkReposeImageReader() override;

  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  void Fail(const std::string& reason);

  char* FileName = nullptr;
  char* SeriesUID = nullptr;
  std::string LastError;
  vtkSmartPointer<vtkImageData> DicomVolume; // a DICOM series read by RequestInformation

private:
  vtkReposeImageReader(const vtkReposeImageReader&) = delete;
  void operator=(const vtkReposeImageReader&) = delete;
};

#endif
