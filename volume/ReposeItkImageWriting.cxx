#include "ReposeItkImageWriting.h"

#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkMatrix3x3.h"
#include "vtkPointData.h"

#include "itkImage.h"
#include "itkImageFileWriter.h"
#include "itkMetaDataObject.h"
#include "itkMetaImageIOFactory.h"
#include "itkNiftiImageIOFactory.h"
#include "itkNrrdImageIOFactory.h"
#include "itkVector.h"

#include "vtkReposeVersion.h"

#include <algorithm>
#include <mutex>
#include <stdexcept>

namespace
{
// The version and `fields` as NRRD and MetaImage write them: key/value fields from the image's dictionary.
itk::MetaDataDictionary HeaderNotes(const std::vector<std::pair<std::string, std::string>>& fields)
{
  itk::MetaDataDictionary notes;
  itk::EncapsulateMetaData<std::string>(notes, vtkReposeVersion::GetKey(), vtkReposeVersion::GetVersion());
  for (const auto& [key, value] : fields)
  {
    itk::EncapsulateMetaData<std::string>(notes, key, value);
  }
  return notes;
}

template <class T>
void WriteTyped(
  vtkImageData* input, const std::string& fileName, bool compress, const itk::MetaDataDictionary& notes)
{
  using ImageType = itk::Image<T, 3>;
  typename ImageType::Pointer image = ImageType::New();
  int dims[3];
  input->GetDimensions(dims);
  typename ImageType::RegionType region;
  typename ImageType::SpacingType spacing;
  typename ImageType::PointType origin;
  typename ImageType::DirectionType direction;
  const double* o = input->GetOrigin();
  const double* s = input->GetSpacing();
  vtkMatrix3x3* d = input->GetDirectionMatrix();
  int extent[6];
  input->GetExtent(extent);
  for (int a = 0; a < 3; ++a)
  {
    region.SetIndex(a, 0);
    region.SetSize(a, static_cast<itk::SizeValueType>(dims[a]));
    spacing[a] = s[a];
    for (int b = 0; b < 3; ++b)
    {
      direction(a, b) = d->GetElement(a, b);
    }
  }
  // A VTK extent not starting at 0 moves the first voxel: origin + D * diag(spacing) * extentStart.
  for (int a = 0; a < 3; ++a)
  {
    double x = o[a];
    for (int b = 0; b < 3; ++b)
    {
      x += d->GetElement(a, b) * s[b] * extent[2 * b];
    }
    origin[a] = x;
  }
  image->SetRegions(region);
  image->SetSpacing(spacing);
  image->SetOrigin(origin);
  image->SetDirection(direction);
  image->SetMetaDataDictionary(notes);
  image->Allocate();
  const T* src = static_cast<const T*>(input->GetPointData()->GetScalars()->GetVoidPointer(0));
  std::copy(src, src + region.GetNumberOfPixels(), image->GetBufferPointer());

  using WriterType = itk::ImageFileWriter<ImageType>;
  typename WriterType::Pointer writer = WriterType::New();
  writer->SetFileName(fileName);
  writer->SetInput(image);
  writer->SetUseCompression(compress);
  writer->Update();
}

void WriteByType(
  vtkImageData* input, const std::string& fileName, bool compress, const itk::MetaDataDictionary& notes)
{
  if (input->GetPointData()->GetScalars()->GetNumberOfComponents() == 3)
  {
    // A displacement field: ITK's vector image (NIfTI intent "vector", MetaImage 3 channels).
    WriteTyped<itk::Vector<float, 3>>(input, fileName, compress, notes);
    return;
  }
  switch (input->GetScalarType())
  {
    case VTK_INT:
      WriteTyped<int>(input, fileName, compress, notes);
      break;
    case VTK_SHORT:
      WriteTyped<short>(input, fileName, compress, notes);
      break;
    case VTK_UNSIGNED_CHAR:
      WriteTyped<unsigned char>(input, fileName, compress, notes);
      break;
    case VTK_UNSIGNED_SHORT:
      WriteTyped<unsigned short>(input, fileName, compress, notes);
      break;
    case VTK_FLOAT:
      WriteTyped<float>(input, fileName, compress, notes);
      break;
    case VTK_DOUBLE:
      WriteTyped<double>(input, fileName, compress, notes);
      break;
    default:
      throw std::runtime_error(std::string("unsupported scalar type ") + input->GetScalarTypeAsString() +
        " (use int, short, unsigned short, unsigned char, float or double)");
  }
}
}

namespace repose_vtk
{
void RegisterItkImageFactories()
{
  static std::once_flag once;
  std::call_once(once, [] {
    itk::NiftiImageIOFactory::RegisterOneFactory();
    itk::NrrdImageIOFactory::RegisterOneFactory();
    itk::MetaImageIOFactory::RegisterOneFactory();
  });
}

void WriteWithItk(vtkImageData* input, const std::string& fileName, bool compress,
  const std::vector<std::pair<std::string, std::string>>& fields)
{
  WriteByType(input, fileName, compress, HeaderNotes(fields));
}
}
