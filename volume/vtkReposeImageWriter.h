#ifndef vtkReposeImageWriter_h
#define vtkReposeImageWriter_h
// Writes 3-D scalar vtkImageData (int, short, unsigned short, unsigned char, float, double; or 3 floats, a vector
// field) through ITK with its origin, spacing and direction matrix. Format by extension: .nii,
// .nii.gz (compressed), .nrrd, .mha, .nhdr, .mhd, or .vti (VTK's XML image data, with
// its direction, for ParaView; written by VTK). Output is written under a temporary name in the target directory and renamed
// into place, so a failed or interrupted write never leaves a partial file under the final name.

#include "ReposeVolumeModule.h"
#include "vtkImageAlgorithm.h"

#include <string>

class vtkImageData;

class REPOSEVOLUME_EXPORT vtkReposeImageWriter : public vtkImageAlgorithm
{
public:
  static vtkReposeImageWriter* New();
  vtkTypeMacro(vtkReposeImageWriter, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  vtkSetStringMacro(FileName);
  vtkGetStringMacro(FileName);

  /// Integer images (label volumes) are written in the smallest integer type that holds their
  /// values: unsigned char up to 255, unsigned short up to 65535, short for small negative values,
  /// else as given. A label volume of a few hundred labels is then 2-4 times smaller to store and to
  /// compress, and 3D Slicer and ITK read it as the segmentation type they expect. Off by default;
  /// float and double images are never changed.
  vtkSetMacro(SmallestIntegerType, bool);
  vtkGetMacro(SmallestIntegerType, bool);
  vtkBooleanMacro(SmallestIntegerType, bool);

  /// Updates the input and writes it. Returns 1 on success, 0 on failure (see GetLastError()).
  int Write();

  /// One-line description of the last failure ("FILE: cannot write (reason)"), empty after success.
  const char* GetLastError() { return this->LastError.c_str(); }

protected:
  vtkReposeImageWriter();
  ~vtkReposeImageWriter() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int FillOutputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int WriteImage(vtkImageData* image);

  char* FileName = nullptr;
  bool SmallestIntegerType = false;
  std::string LastError;

private:
  vtkReposeImageWriter(const vtkReposeImageWriter&) = delete;
  void operator=(const vtkReposeImageWriter&) = delete;
};

#endif
