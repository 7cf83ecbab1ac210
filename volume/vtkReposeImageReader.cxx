#include "vtkReposeImageReader.h"

#include "vtkDataArray.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkMatrix3x3.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkStreamingDemandDrivenPipeline.h"

#include "itkImage.h"
#include "itkImageFileReader.h"
#include "itkImageIOFactory.h"
#include "itkMetaImageIOFactory.h"
#include "itkNiftiImageIOFactory.h"
#include "itkNrrdImageIOFactory.h"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <mutex>
#include <stdexcept>

vtkStandardNewMacro(vtkReposeImageReader);

namespace
{
void RegisterItkFactories()
{
  static std::once_flag once;
  std::call_once(once, [] {
    itk::NiftiImageIOFactory::RegisterOneFactory();
    itk::NrrdImageIOFactory::RegisterOneFactory();
    itk::MetaImageIOFactory::RegisterOneFactory();
  });
}

struct Header
{
  bool IsFloat = false;
  int Extent[6] = { 0, -1, 0, -1, 0, -1 };
  double Origin[3] = { 0, 0, 0 };
  double Spacing[3] = { 1, 1, 1 };
  double Direction[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 1 };
};

// Throws std::runtime_error with a short reason.
bool IsFloatFile(const char* fileName)
{
  std::ifstream probe(fileName, std::ios::binary);
  if (!probe)
  {
    throw std::runtime_error("file does not exist or is not readable");
  }
  itk::ImageIOBase::Pointer io =
    itk::ImageIOFactory::CreateImageIO(fileName, itk::ImageIOFactory::FileModeEnum::ReadMode);
  if (!io)
  {
    throw std::runtime_error("unknown or unsupported image format");
  }
  io->SetFileName(fileName);
  io->ReadImageInformation();
  if (io->GetNumberOfDimensions() > 3)
  {
    throw std::runtime_error(
      "image has " + std::to_string(io->GetNumberOfDimensions()) + " dimensions, expected 3");
  }
  if (io->GetNumberOfComponents() != 1)
  {
    throw std::runtime_error("image has " + std::to_string(io->GetNumberOfComponents()) +
      " components per voxel, expected a scalar image");
  }
  const auto type = io->GetComponentType();
  return type == itk::IOComponentEnum::FLOAT || type == itk::IOComponentEnum::DOUBLE;
}

template <class T>
typename itk::ImageFileReader<itk::Image<T, 3>>::Pointer MakeReader(const char* fileName, Header& h)
{
  using ReaderType = itk::ImageFileReader<itk::Image<T, 3>>;
  typename ReaderType::Pointer reader = ReaderType::New();
  reader->SetFileName(fileName);
  reader->UpdateOutputInformation();
  auto* image = reader->GetOutput();
  const auto region = image->GetLargestPossibleRegion();
  for (int a = 0; a < 3; ++a)
  {
    h.Extent[2 * a] = 0;
    h.Extent[2 * a + 1] = static_cast<int>(region.GetSize()[a]) - 1;
    h.Origin[a] = image->GetOrigin()[a];
    h.Spacing[a] = image->GetSpacing()[a];
    for (int b = 0; b < 3; ++b)
    {
      h.Direction[3 * a + b] = image->GetDirection()(a, b);
    }
  }
  return reader;
}

Header ReadHeader(const char* fileName)
{
  Header h;
  h.IsFloat = IsFloatFile(fileName);
  if (h.IsFloat)
  {
    MakeReader<float>(fileName, h);
  }
  else
  {
    MakeReader<int>(fileName, h);
  }
  return h;
}

template <class T, class ArrayT>
vtkSmartPointer<vtkDataArray> ReadPixels(const char* fileName, Header& h)
{
  auto reader = MakeReader<T>(fileName, h);
  reader->Update();
  auto* image = reader->GetOutput();
  const std::size_t n = image->GetLargestPossibleRegion().GetNumberOfPixels();
  auto array = vtkSmartPointer<ArrayT>::New();
  array->SetName("ImageScalars");
  array->SetNumberOfTuples(static_cast<vtkIdType>(n));
  std::copy(image->GetBufferPointer(), image->GetBufferPointer() + n, array->GetPointer(0));
  return array;
}

void ApplyHeader(const Header& h, vtkInformation* outInfo)
{
  outInfo->Set(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), h.Extent, 6);
  outInfo->Set(vtkDataObject::ORIGIN(), h.Origin, 3);
  outInfo->Set(vtkDataObject::SPACING(), h.Spacing, 3);
  outInfo->Set(vtkDataObject::DIRECTION(), h.Direction, 9);
  vtkDataObject::SetPointDataActiveScalarInfo(outInfo, h.IsFloat ? VTK_FLOAT : VTK_INT, 1);
}
}

vtkReposeImageReader::vtkReposeImageReader()
{
  this->SetNumberOfInputPorts(0);
  this->SetNumberOfOutputPorts(1);
}

vtkReposeImageReader::~vtkReposeImageReader()
{
  this->SetFileName(nullptr);
}

void vtkReposeImageReader::Fail(const std::string& reason)
{
  this->LastError =
    std::string(this->FileName ? this->FileName : "(no file name)") + ": cannot read (" + reason + ")";
  vtkErrorMacro(<< this->LastError);
}

int vtkReposeImageReader::RequestInformation(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  this->LastError.clear();
  if (!this->FileName || !*this->FileName)
  {
    this->Fail("no file name set");
    return 0;
  }
  RegisterItkFactories();
  try
  {
    const Header h = ReadHeader(this->FileName);
    ApplyHeader(h, outputVector->GetInformationObject(0));
  }
  catch (const itk::ExceptionObject& e)
  {
    this->Fail(e.GetDescription());
    return 0;
  }
  catch (const std::exception& e)
  {
    this->Fail(e.what());
    return 0;
  }
  return 1;
}

int vtkReposeImageReader::RequestData(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  vtkImageData* output = vtkImageData::GetData(outInfo);
  if (!this->FileName || !*this->FileName)
  {
    this->Fail("no file name set");
    return 0;
  }
  RegisterItkFactories();
  try
  {
    Header h;
    h.IsFloat = IsFloatFile(this->FileName);
    vtkSmartPointer<vtkDataArray> scalars = h.IsFloat
      ? ReadPixels<float, vtkFloatArray>(this->FileName, h)
      : ReadPixels<int, vtkIntArray>(this->FileName, h);
    output->Initialize();
    output->SetExtent(h.Extent);
    output->SetOrigin(h.Origin);
    output->SetSpacing(h.Spacing);
    output->SetDirectionMatrix(h.Direction);
    output->GetPointData()->SetScalars(scalars);
  }
  catch (const itk::ExceptionObject& e)
  {
    this->Fail(e.GetDescription());
    return 0;
  }
  catch (const std::exception& e)
  {
    this->Fail(e.what());
    return 0;
  }
  this->LastError.clear();
  return 1;
}

void vtkReposeImageReader::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
  os << indent << "LastError: " << this->LastError << "\n";
}
