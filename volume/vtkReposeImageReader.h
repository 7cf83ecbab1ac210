#ifndef vtkReposeImageReader_h
#define vtkReposeImageReader_h
// Reads a 3-D scalar image through ITK (NIfTI .nii/.nii.gz, NRRD .nrrd/.nhdr, MetaImage .mha/.mhd)
// into vtkImageData with the file's origin, spacing and direction matrix (ITK's LPS frame).
// Integer pixels become VTK_INT, floating-point pixels VTK_FLOAT; the scalars are named "ImageScalars".

#include "ReposeVolumeModule.h"
#include "vtkImageAlgorithm.h"

#include <string>

class REPOSEVOLUME_EXPORT vtkReposeImageReader : public vtkImageAlgorithm
{
public:
  static vtkReposeImageReader* New();
  vtkTypeMacro(vtkReposeImageReader, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  vtkSetStringMacro(FileName);
  vtkGetStringMacro(FileName);

  /// One-line description of the last failure ("FILE: cannot read (reason)"), empty after success.
  const char* GetLastError() { return this->LastError.c_str(); }

protected:
  vtkReposeImageReader();
  ~vtkReposeImageReader() override;

  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  void Fail(const std::string& reason);

  char* FileName = nullptr;
  std::string LastError;

private:
  vtkReposeImageReader(const vtkReposeImageReader&) = delete;
  void operator=(const vtkReposeImageReader&) = delete;
};

#endif
