#include "vtkReposeImageReader.h"

#include "ReposeItkImageWriting.h"  // RegisterItkImageFactories, shared with the writer

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
#include "vtkStringArray.h"
#include "vtkFieldData.h"

#include "itkImage.h"
#include "itkImageFileReader.h"
#include "itkImageIOFactory.h"
#include "itkMetaImageIOFactory.h"
#include "itkNiftiImageIOFactory.h"
#include "itkNrrdImageIOFactory.h"

#include "ReposeDicomSeries.h"
#include "image_file_integrity.h"
#include "array_names.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <stdexcept>

vtkStandardNewMacro(vtkReposeImageReader);

namespace
{
struct Header
{
  bool IsFloat = false;
  int Extent[6] = { 0, -1, 0, -1, 0, -1 };
  double Origin[3] = { 0, 0, 0 };
  double Spacing[3] = { 1, 1, 1 };
  double Direction[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 1 };
};

// Bounds beyond which a grid is damage, not anatomy: a voxel of a metre, an origin a thousand
// kilometres away, more voxels than 32-bit indices address.
constexpr double kMaxSpacingMm = 1000.0;
constexpr double kMaxOriginMm = 1e9;
constexpr double kMaxVoxels = 4294967295.0;

struct FileKind
{
  bool IsFloat = false;
  bool WideIntegers = false; // values may not fit an int: read as double, checked
  std::uint64_t VoxelBytes = 0;
};

std::string Number(double x)
{
  std::ostringstream text;
  text << x;
  return text.str();
}

// Throws std::runtime_error with a short reason.
FileKind ProbeFile(const char* fileName)
{
  std::ifstream probe(fileName, std::ios::binary);
  if (!probe)
  {
    throw std::runtime_error("file does not exist or is not readable");
  }
  repose::checkImageHeader(fileName);
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
  double voxels = 1;
  for (unsigned a = 0; a < io->GetNumberOfDimensions(); ++a)
  {
    voxels *= static_cast<double>(io->GetDimensions(a));
  }
  if (voxels < 1 || voxels > kMaxVoxels)
  {
    throw std::runtime_error("header claims " + Number(voxels) + " voxels");
  }
  using C = itk::IOComponentEnum;
  const auto type = io->GetComponentType();
  FileKind kind;
  kind.IsFloat = type == C::FLOAT || type == C::DOUBLE;
  kind.WideIntegers = type == C::UINT || type == C::LONG || type == C::ULONG || type == C::LONGLONG ||
    type == C::ULONGLONG;
  kind.VoxelBytes = static_cast<std::uint64_t>(voxels) * io->GetComponentSize();
  return kind;
}

void CheckGrid(const Header& h)
{
  for (int a = 0; a < 3; ++a)
  {
    if (!std::isfinite(h.Spacing[a]) || h.Spacing[a] <= 0 || h.Spacing[a] > kMaxSpacingMm)
    {
      throw std::runtime_error("voxel spacing " + Number(h.Spacing[a]) + " mm along axis " +
        std::to_string(a) + " is not in (0, " + Number(kMaxSpacingMm) + "] mm");
    }
    if (!std::isfinite(h.Origin[a]) || std::fabs(h.Origin[a]) > kMaxOriginMm)
    {
      throw std::runtime_error("origin " + Number(h.Origin[a]) + " mm is not a sane coordinate");
    }
  }
  const double* d = h.Direction;
  for (int i = 0; i < 9; ++i)
  {
    if (!std::isfinite(d[i]))
    {
      throw std::runtime_error("direction matrix is not finite");
    }
  }
  const double det = d[0] * (d[4] * d[8] - d[5] * d[7]) - d[1] * (d[3] * d[8] - d[5] * d[6]) +
    d[2] * (d[3] * d[7] - d[4] * d[6]);
  if (std::fabs(std::fabs(det) - 1) > 1e-3)
  {
    throw std::runtime_error("direction matrix is not a rotation (determinant " + Number(det) + ")");
  }
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
  CheckGrid(h);
  return reader;
}

Header ReadHeader(const char* fileName)
{
  Header h;
  h.IsFloat = ProbeFile(fileName).IsFloat;
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
  array->SetName(repose::arrays::kImageScalars);
  array->SetNumberOfTuples(static_cast<vtkIdType>(n));
  std::copy(image->GetBufferPointer(), image->GetBufferPointer() + n, array->GetPointer(0));
  return array;
}

// Integers of 32-bit unsigned or 64-bit files, read exactly through double and refused when they
// do not fit an int (3 000 000 000 would otherwise wrap to a negative label).
vtkSmartPointer<vtkDataArray> ReadWideIntegers(const char* fileName, Header& h)
{
  auto reader = MakeReader<double>(fileName, h);
  reader->Update();
  auto* image = reader->GetOutput();
  const std::size_t n = image->GetLargestPossibleRegion().GetNumberOfPixels();
  const double* values = image->GetBufferPointer();
  auto array = vtkSmartPointer<vtkIntArray>::New();
  array->SetName(repose::arrays::kImageScalars);
  array->SetNumberOfTuples(static_cast<vtkIdType>(n));
  for (std::size_t i = 0; i < n; ++i)
  {
    if (values[i] < -2147483648.0 || values[i] > 2147483647.0)
    {
      throw std::runtime_error("voxel value " + std::to_string(static_cast<long long>(values[i])) +
        " does not fit a 32-bit signed integer");
    }
    array->SetValue(static_cast<vtkIdType>(i), static_cast<int>(values[i]));
  }
  return array;
}

// A DICOM series as vtkImageData: float voxels after rescale, ITK's geometry, the patient and
// study attributes in the field data.
vtkSmartPointer<vtkImageData> ReadDicomFolder(const char* folder, const char* seriesUID)
{
  const repose::DicomSeriesVolume series = repose::ReadDicomSeries(folder, seriesUID ? seriesUID : "");
  const auto* image = series.Image.GetPointer();
  const auto size = image->GetLargestPossibleRegion().GetSize();
  Header h;
  h.IsFloat = true;
  for (int a = 0; a < 3; ++a)
  {
    h.Extent[2 * a + 1] = static_cast<int>(size[a]) - 1;
    h.Origin[a] = image->GetOrigin()[a];
    h.Spacing[a] = image->GetSpacing()[a];
    for (int b = 0; b < 3; ++b)
    {
      h.Direction[3 * a + b] = image->GetDirection()(a, b);
    }
  }
  CheckGrid(h);
  const std::size_t n = image->GetLargestPossibleRegion().GetNumberOfPixels();
  auto values = vtkSmartPointer<vtkFloatArray>::New();
  values->SetName("ImageScalars");
  values->SetNumberOfTuples(static_cast<vtkIdType>(n));
  for (std::size_t i = 0; i < n; ++i)
  {
    if (!std::isfinite(image->GetBufferPointer()[i]))
    {
      throw std::runtime_error("voxel " + std::to_string(i) + " is not a finite number");
    }
  }
  std::copy(image->GetBufferPointer(), image->GetBufferPointer() + n, values->GetPointer(0));
  auto out = vtkSmartPointer<vtkImageData>::New();
  out->SetExtent(h.Extent);
  out->SetOrigin(h.Origin);
  out->SetSpacing(h.Spacing);
  out->SetDirectionMatrix(h.Direction);
  out->GetPointData()->SetScalars(values);
  auto tags = vtkSmartPointer<vtkStringArray>::New();
  tags->SetName("DicomTags");
  for (const auto& [key, value] : series.PatientAndStudy)
  {
    tags->InsertNextValue(key + "=" + value);
  }
  out->GetFieldData()->AddArray(tags);
  return out;
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
  this->SetSeriesUID(nullptr);
}

void vtkReposeImageReader::Fail(const std::string& reason)
{
  // ITK's descriptions span lines; a user reads one.
  std::string oneLine;
  for (char c : reason)
  {
    if (c == '\n' || c == '\r')
    {
      c = ' ';
    }
    if (c != ' ' || (!oneLine.empty() && oneLine.back() != ' '))
    {
      oneLine += c;
    }
  }
  const auto itkPrefix = oneLine.find("): ");
  if ((oneLine.rfind("ITK ERROR: ", 0) == 0 || oneLine.rfind("itk::ERROR: ", 0) == 0) && itkPrefix != std::string::npos)
  {
    oneLine = oneLine.substr(itkPrefix + 3);
  }
  while (!oneLine.empty() && oneLine.back() == ' ')
  {
    oneLine.pop_back();
  }
  this->LastError =
    std::string(this->FileName ? this->FileName : "(no file name)") + ": cannot read (" + oneLine + ")";
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
  repose_vtk::RegisterItkImageFactories();
  this->DicomVolume = nullptr;
  try
  {
    if (std::filesystem::is_directory(this->FileName))
    {
      // A series' geometry needs every slice's header: read it all once, here.
      this->DicomVolume = ReadDicomFolder(this->FileName, this->SeriesUID);
      vtkInformation* outInfo = outputVector->GetInformationObject(0);
      outInfo->Set(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), this->DicomVolume->GetExtent(), 6);
      outInfo->Set(vtkDataObject::ORIGIN(), this->DicomVolume->GetOrigin(), 3);
      outInfo->Set(vtkDataObject::SPACING(), this->DicomVolume->GetSpacing(), 3);
      outInfo->Set(vtkDataObject::DIRECTION(), this->DicomVolume->GetDirectionMatrix()->GetData(), 9);
      vtkDataObject::SetPointDataActiveScalarInfo(outInfo, VTK_FLOAT, 1);
      return 1;
    }
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
  repose_vtk::RegisterItkImageFactories();
  try
  {
    if (std::filesystem::is_directory(this->FileName))
    {
      vtkSmartPointer<vtkImageData> series = this->DicomVolume;
      this->DicomVolume = nullptr;
      output->ShallowCopy(series ? series.GetPointer() : ReadDicomFolder(this->FileName, this->SeriesUID).GetPointer());
      this->LastError.clear();
      return 1;
    }
    Header h;
    const FileKind kind = ProbeFile(this->FileName);
    h.IsFloat = kind.IsFloat;
    repose::checkImageFileIntegrity(this->FileName, kind.VoxelBytes);
    vtkSmartPointer<vtkDataArray> scalars = h.IsFloat ? ReadPixels<float, vtkFloatArray>(this->FileName, h)
      : kind.WideIntegers                             ? ReadWideIntegers(this->FileName, h)
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
  os << indent << "SeriesUID: " << (this->SeriesUID ? this->SeriesUID : "(none)") << "\n";
  os << indent << "LastError: " << this->LastError << "\n";
}
