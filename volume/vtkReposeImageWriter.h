#ifndef vtkReposeImageWriter_h
#define vtkReposeImageWriter_h
// Writes 3-D scalar vtkImageData (int, short, unsigned short, unsigned char, float, double; or 3 floats, a vector
// field) through ITK with its origin, spacing and direction matrix. Format by extension: .nii,
// .nii.gz, .nrrd (gzip-encoded), .mha and .mhd (zlib), .nhdr (raw), or .vti (VTK's XML image data, with
// its direction, for ParaView; written by VTK). Output is written under a temporary name in the target directory and renamed
// into place, so a failed or interrupted write never leaves a partial file under the final name.

#include "ReposeVolumeModule.h"
#include "vtkReposeWriterBase.h"

#include <string>
#include <utility>
#include <vector>

class vtkImageData;

class REPOSEVOLUME_EXPORT vtkReposeImageWriter : public vtkReposeWriterBase
{
public:
  static vtkReposeImageWriter* New();
  vtkTypeMacro(vtkReposeImageWriter, vtkReposeWriterBase);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// Integer images (label volumes) are written in the smallest integer type that holds their
  /// values: unsigned char up to 255, unsigned short up to 65535, short for small negative values,
  /// else as given. A label volume of a few hundred labels is then 2-4 times smaller to store and to
  /// compress, and 3D Slicer and ITK read it as the segmentation type they expect. Off by default;
  /// float and double images are never changed.
  vtkSetMacro(SmallestIntegerType, bool);
  vtkGetMacro(SmallestIntegerType, bool);
  vtkBooleanMacro(SmallestIntegerType, bool);

  /// What the file holds, after "Repose VERSION " in a NIfTI's descrip field ("posed labels"). Unset:
  /// "labels" with SmallestIntegerType, "displacement field" for 3 components, else "image". NRRD,
  /// MetaImage and .vti files carry the version as a field of their own (vtkReposeVersion).
  vtkSetStringMacro(Description);
  vtkGetStringMacro(Description);

protected:
  vtkReposeImageWriter();
  ~vtkReposeImageWriter() override;

  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int WriteImage(vtkImageData* image);
  /// Key/value fields a subclass adds to a NRRD or MetaImage header (after ReposeVersion), given
  /// the image as it is written. None here. May throw std::exception (its what() the reason).
  virtual std::vector<std::pair<std::string, std::string>> HeaderFields(vtkImageData* written);

  bool SmallestIntegerType = false;
  char* Description = nullptr;

private:
  vtkReposeImageWriter(const vtkReposeImageWriter&) = delete;
  void operator=(const vtkReposeImageWriter&) = delete;
};

#endif
