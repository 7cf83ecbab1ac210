#ifndef ReposeItkImageWriting_h
#define ReposeItkImageWriting_h
// An image written by ITK's NIfTI, NRRD or MetaImage IO (by the file name's extension), with the
// image's origin, spacing and direction, and key/value header fields where the format keeps them.

#include <string>
#include <utility>
#include <vector>

class vtkImageData;

namespace repose_vtk
{
/// Registers ITK's NIfTI, NRRD and MetaImage IO factories (once per process).
void RegisterItkImageFactories();

/// Writes input's scalars (int, short, unsigned short, unsigned char, float or double; three float
/// components: a displacement field as ITK's vector image) to fileName, compressed when asked, with
/// Repose's version and `fields` in the header (NRRD, MetaImage). Throws std::runtime_error for
/// another scalar type and itk::ExceptionObject when ITK fails.
void WriteWithItk(vtkImageData* input, const std::string& fileName, bool compress,
  const std::vector<std::pair<std::string, std::string>>& fields);
}

#endif
