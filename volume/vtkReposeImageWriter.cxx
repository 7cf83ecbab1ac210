#include "vtkReposeImageWriter.h"

#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMatrix3x3.h"
#include "vtkObjectFactory.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkSmartPointer.h"
#include "vtkXMLImageDataWriter.h"

#include "itkImage.h"
#include "itkImageFileWriter.h"
#include "itkMetaDataObject.h"
#include "itkVector.h"
#include "itkMetaImageIOFactory.h"
#include "itkNiftiImageIOFactory.h"
#include "itkNrrdImageIOFactory.h"

#include "image_file_integrity.h"
#include "nifti_description.h"
#include "temporary_lock.h"
#include "vtkReposeVersion.h"
#include "written_file.h"

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <system_error>
#include <unistd.h>

vtkStandardNewMacro(vtkReposeImageWriter);

namespace
{
namespace fs = std::filesystem;

void RegisterItkFactories()
{
  static std::once_flag once;
  std::call_once(once, [] {
    itk::NiftiImageIOFactory::RegisterOneFactory();
    itk::NrrdImageIOFactory::RegisterOneFactory();
    itk::MetaImageIOFactory::RegisterOneFactory();
  });
}

bool EndsWith(const std::string& s, const std::string& suffix)
{
  if (s.size() < suffix.size())
  {
    return false;
  }
  std::string tail = s.substr(s.size() - suffix.size());
  std::transform(tail.begin(), tail.end(), tail.begin(), [](unsigned char c) { return std::tolower(c); });
  return tail == suffix;
}

/// Bytes of a file, or of all the files of a folder (a header and its data file).
std::uintmax_t DataBytes(const fs::path& path)
{
  std::error_code ec;
  if (!fs::is_directory(path, ec))
  {
    const std::uintmax_t n = fs::file_size(path, ec);
    return ec ? 0 : n;
  }
  std::uintmax_t total = 0;
  for (const auto& entry : fs::directory_iterator(path, ec))
  {
    total += DataBytes(entry.path());
  }
  return total;
}

// A compressed NRRD or MetaImage read back: every stream inflates whole, to all the voxels.
void RequireCompleteData(const std::string& target, const std::string& written, std::uintmax_t voxelBytes)
{
  try
  {
    repose::checkImageFileIntegrity(written, voxelBytes);
  }
  catch (const std::runtime_error&)
  {
    repose::throwWriteFailure(target, written);
  }
}

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
void WriteWithItk(
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

// VTK's XML image data (ParaView's .vti): origin, spacing and the direction matrix, zlib-compressed.
void WriteVti(vtkImageData* input, const std::string& fileName)
{
  vtkNew<vtkImageData> stamped;
  stamped->ShallowCopy(input);
  vtkReposeVersion::Stamp(stamped);
  vtkNew<vtkXMLImageDataWriter> writer;
  writer->SetFileName(fileName.c_str());
  writer->SetInputData(stamped);
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  writer->SetCompressorTypeToZLib();
  if (!writer->Write() || writer->GetErrorCode() != 0)
  {
    throw std::runtime_error("VTK's XML image writer failed");
  }
}

// The smallest VTK integer type that holds [lo, hi], or `type` itself when none is smaller.
int SmallestIntegerType(int type, double lo, double hi)
{
  if (lo >= 0 && hi <= VTK_UNSIGNED_CHAR_MAX)
  {
    return VTK_UNSIGNED_CHAR;
  }
  if (lo >= 0 && hi <= VTK_UNSIGNED_SHORT_MAX && vtkDataArray::GetDataTypeSize(type) > 2)
  {
    return VTK_UNSIGNED_SHORT;
  }
  if (lo >= VTK_SHORT_MIN && hi <= VTK_SHORT_MAX && vtkDataArray::GetDataTypeSize(type) > 2)
  {
    return VTK_SHORT;
  }
  return type;
}

// `input` cast to the smallest integer type holding its values (see SmallestIntegerType), or
// `input` itself when it is not an integer image or is already that small.
vtkSmartPointer<vtkImageData> WithSmallestIntegerType(vtkImageData* input)
{
  vtkDataArray* scalars = input->GetPointData()->GetScalars();
  const int type = input->GetScalarType();
  if (scalars->GetNumberOfComponents() != 1 || type == VTK_FLOAT || type == VTK_DOUBLE)
  {
    return input;
  }
  double range[2];
  scalars->GetRange(range);
  const int smallest = SmallestIntegerType(type, range[0], range[1]);
  if (smallest == type)
  {
    return input;
  }
  // CopyStructure keeps the extent, origin, spacing and direction; DeepCopy converts the values.
  auto narrowed = vtkSmartPointer<vtkImageData>::New();
  narrowed->CopyStructure(input);
  vtkSmartPointer<vtkDataArray> values = vtk::TakeSmartPointer(vtkDataArray::CreateDataArray(smallest));
  values->DeepCopy(scalars);
  values->SetName(scalars->GetName());
  narrowed->GetPointData()->SetScalars(values);
  return narrowed;
}

void WriteByType(
  vtkImageData* input, const std::string& fileName, bool compress, const itk::MetaDataDictionary& notes)
{
  if (input->GetPointData()->GetScalars()->GetNumberOfComponents() == 3)
  {
    // A displacement field: ITK's vector image (NIfTI intent "vector", MetaImage 3 channels).
    WriteWithItk<itk::Vector<float, 3>>(input, fileName, compress, notes);
    return;
  }
  switch (input->GetScalarType())
  {
    case VTK_INT:
      WriteWithItk<int>(input, fileName, compress, notes);
      break;
    case VTK_SHORT:
      WriteWithItk<short>(input, fileName, compress, notes);
      break;
    case VTK_UNSIGNED_CHAR:
      WriteWithItk<unsigned char>(input, fileName, compress, notes);
      break;
    case VTK_UNSIGNED_SHORT:
      WriteWithItk<unsigned short>(input, fileName, compress, notes);
      break;
    case VTK_FLOAT:
      WriteWithItk<float>(input, fileName, compress, notes);
      break;
    case VTK_DOUBLE:
      WriteWithItk<double>(input, fileName, compress, notes);
      break;
    default:
      throw std::runtime_error(std::string("unsupported scalar type ") + input->GetScalarTypeAsString() +
        " (use int, short, unsigned short, unsigned char, float or double)");
  }
}
}

vtkReposeImageWriter::vtkReposeImageWriter() = default;

vtkReposeImageWriter::~vtkReposeImageWriter()
{
  this->SetDescription(nullptr);
}

std::vector<std::pair<std::string, std::string>> vtkReposeImageWriter::HeaderFields(vtkImageData*)
{
  return {};
}

int vtkReposeImageWriter::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector*)
{
  vtkImageData* input = vtkImageData::GetData(inputVector[0]);
  return this->WriteImage(input);
}

int vtkReposeImageWriter::WriteImage(vtkImageData* given)
{
  const std::string target = this->FileName ? this->FileName : "";
  auto fail = [this](const std::string& reason) { return this->Fail(reason); };
  if (target.empty())
  {
    return fail("no file name set");
  }
  if (!given || !given->GetPointData()->GetScalars() || given->GetNumberOfPoints() < 1)
  {
    return fail("input has no image scalars");
  }
  const vtkSmartPointer<vtkImageData> input =
    this->SmallestIntegerType ? WithSmallestIntegerType(given) : vtkSmartPointer<vtkImageData>(given);
  const int components = input->GetPointData()->GetScalars()->GetNumberOfComponents();
  if (components != 1 && !(components == 3 && input->GetScalarType() == VTK_FLOAT))
  {
    return fail("input scalars must have one component (or three floats: a vector field)");
  }
  const bool gzipNifti = EndsWith(target, ".nii.gz");
  // NRRD (gzip encoding) and MetaImage (zlib) compressed as .nii.gz is: a label volume shrinks
  // tens of times. A detached .nhdr keeps raw data, which is why one asks for a detached header.
  const bool compress =
    gzipNifti || EndsWith(target, ".nrrd") || EndsWith(target, ".mha") || EndsWith(target, ".mhd");
  const bool pair = EndsWith(target, ".mhd") || EndsWith(target, ".nhdr");
  const bool vti = EndsWith(target, ".vti");
  const bool nifti = gzipNifti || EndsWith(target, ".nii");
  if (!(compress || pair || vti || EndsWith(target, ".nii")))
  {
    return fail("unknown extension; use .nii, .nii.gz, .nrrd, .nhdr, .mha, .mhd or .vti");
  }
  RegisterItkFactories();

  const fs::path finalPath(target);
  fs::path dir = finalPath.parent_path();
  if (dir.empty())
  {
    dir = ".";
  }
  const std::string base = finalPath.filename().string();
  const std::string tag = ".repose-tmp-" + std::to_string(::getpid()) + "-";
  std::error_code ec;
  // Written into a temporary folder under the final name (a header+data pair's relative data-file
  // reference stays valid), locked while this process writes it, then moved out.
  const fs::path tmpDir = dir / (tag + base + ".d");
  const fs::path tmpFile = tmpDir / base;
  if (!fs::is_directory(dir, ec))
  {
    return fail("directory " + dir.string() + " does not exist");
  }
  std::unique_ptr<repose::TemporaryLock> lock;  // held until the folder is gone, removed on failure too
  try
  {
    lock = std::make_unique<repose::TemporaryLock>(tmpDir.string(), true);
  }
  catch (const std::exception& e)
  {
    return fail(e.what());  // not ours to remove: another process writes it
  }
  // ITK's NIfTI writer reports short writes on stderr only: the file is read back to its last byte.
  const std::uintmax_t voxelBytes = std::uintmax_t(input->GetNumberOfPoints()) *
    std::uintmax_t(input->GetScalarSize()) * std::uintmax_t(components);
  try
  {
    errno = 0;
    if (vti)
    {
      WriteVti(input, tmpFile.string());
    }
    else
    {
      // NIfTI's note is set after ITK writes it uncompressed (ITK 5.2 leaves descrip empty).
      const fs::path itkFile = gzipNifti ? tmpDir / base.substr(0, base.size() - 3) : tmpFile;
      WriteByType(input, itkFile.string(), compress && !gzipNifti, HeaderNotes(this->HeaderFields(input)));
      if (nifti)
      {
        if (DataBytes(itkFile) < voxelBytes + 352)
        {
          repose::throwWriteFailure(target, itkFile.string(), errno);
        }
        const std::string what = this->Description ? this->Description
          : components == 3                        ? "displacement field"
          : this->SmallestIntegerType              ? "labels"
                                                   : "image";
        repose::describeNifti(target, itkFile.string(), std::string("Repose ") + vtkReposeVersion::GetVersion() +
            " " + what, gzipNifti ? tmpFile.string() : "");
      }
    }
    if (!fs::exists(tmpFile))
    {
      repose::throwWriteFailure(target, tmpFile.string(), errno);
    }
    if (gzipNifti)
    {
      repose::requireCompleteGzip(target, tmpFile.string(), voxelBytes);
    }
    else if (compress)
    {
      RequireCompleteData(target, tmpFile.string(), voxelBytes);
    }
    repose::requireWritten(target, pair ? tmpDir.string() : tmpFile.string(), 1);
    if (vti)
    {
      repose::requireEndsWith(target, tmpFile.string(), "</VTKFile>\n");
    }
    else if (!compress && DataBytes(pair ? tmpDir : tmpFile) < voxelBytes)
    {
      repose::throwWriteFailure(target, tmpFile.string());
    }
    for (const auto& entry : fs::directory_iterator(tmpDir))
    {
      fs::rename(entry.path(), dir / entry.path().filename());
    }
    fs::remove(tmpDir);
  }
  catch (const repose::WriteFailure& e)
  {
    fs::remove_all(tmpDir, ec);
    return fail(e.reason);
  }
  catch (const itk::ExceptionObject& e)
  {
    // ITK's description runs over lines and names the temporary file: the cause, when known, says more.
    const int err = errno;
    const std::string known = repose::knownWriteFailure(tmpFile.string(), repose::isStorageError(err) ? err : 0);
    fs::remove_all(tmpDir, ec);
    return fail(known.empty() ? e.GetDescription() : known);
  }
  catch (const std::exception& e)
  {
    fs::remove_all(tmpDir, ec);
    return fail(e.what());
  }
  return 1;
}

void vtkReposeImageWriter::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "SmallestIntegerType: " << this->SmallestIntegerType << "\n";
  os << indent << "Description: " << (this->Description ? this->Description : "(from the content)") << "\n";
}
