#include "vtkReposeImageWriter.h"

#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkObjectFactory.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkSmartPointer.h"
#include "vtkXMLImageDataWriter.h"

#include "itkMacro.h"

#include "ReposeItkImageWriting.h"

#include "image_file_integrity.h"
#include "nifti_description.h"
#include "temporary_lock.h"
#include "vtkReposeVersion.h"
#include "written_file.h"

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <system_error>
#include <unistd.h>

vtkStandardNewMacro(vtkReposeImageWriter);

namespace
{
namespace fs = std::filesystem;

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

/// What the file name's extension asks for.
struct ImageFormat
{
  bool gzipNifti; // .nii.gz
  bool nifti;     // .nii or .nii.gz
  bool compress;  // .nii.gz, .nrrd, .mha, .mhd
  bool pair;      // a header and its data file: .mhd, .nhdr
  bool vti;
};

ImageFormat FormatOf(const std::string& target)
{
  ImageFormat f;
  f.gzipNifti = EndsWith(target, ".nii.gz");
  f.nifti = f.gzipNifti || EndsWith(target, ".nii");
  // NRRD (gzip encoding) and MetaImage (zlib) compressed as .nii.gz is: a label volume shrinks
  // tens of times. A detached .nhdr keeps raw data, which is why one asks for a detached header.
  f.compress = f.gzipNifti || EndsWith(target, ".nrrd") || EndsWith(target, ".mha") || EndsWith(target, ".mhd");
  f.pair = EndsWith(target, ".mhd") || EndsWith(target, ".nhdr");
  f.vti = EndsWith(target, ".vti");
  return f;
}

/// The file is written into a temporary folder beside the target under the final name (a
/// header+data pair's relative data-file reference stays valid), locked while this process writes
/// it, then moved out.
struct Staging
{
  fs::path dir;    // the target's folder
  fs::path folder; // the temporary folder
  fs::path file;   // the file in it
  std::unique_ptr<repose::TemporaryLock> lock; // held until the folder is gone, removed on failure too
};

/// The staging of target, or the reason there is none.
std::string Stage(const std::string& target, Staging& staging)
{
  const fs::path finalPath(target);
  staging.dir = finalPath.parent_path().empty() ? fs::path(".") : finalPath.parent_path();
  const std::string base = finalPath.filename().string();
  const std::string tag = ".repose-tmp-" + std::to_string(::getpid()) + "-";
  staging.folder = staging.dir / (tag + base + ".d");
  staging.file = staging.folder / base;
  std::error_code ec;
  if (!fs::is_directory(staging.dir, ec))
  {
    return "directory " + staging.dir.string() + " does not exist";
  }
  try
  {
    staging.lock = std::make_unique<repose::TemporaryLock>(staging.folder.string(), true);
  }
  catch (const std::exception& e)
  {
    return e.what(); // not ours to remove: another process writes it
  }
  return std::string();
}

/// The ITK formats. NIfTI's note is set after ITK writes it uncompressed (ITK 5.2 leaves descrip
/// empty); ITK's NIfTI writer reports short writes on stderr only, so its size is checked first.
void WriteItkStaged(vtkImageData* input, const std::string& target, const ImageFormat& format,
  const Staging& staging, std::uintmax_t voxelBytes,
  const std::vector<std::pair<std::string, std::string>>& fields, const std::string& what)
{
  const std::string base = staging.file.filename().string();
  const fs::path itkFile = format.gzipNifti ? staging.folder / base.substr(0, base.size() - 3) : staging.file;
  repose_vtk::WriteWithItk(input, itkFile.string(), format.compress && !format.gzipNifti, fields);
  if (format.nifti)
  {
    if (DataBytes(itkFile) < voxelBytes + 352)
    {
      repose::throwWriteFailure(target, itkFile.string(), errno);
    }
    repose::describeNifti(target, itkFile.string(),
      std::string("Repose ") + vtkReposeVersion::GetVersion() + " " + what,
      format.gzipNifti ? staging.file.string() : "");
  }
}

/// The staged file read back: there, whole (compressed streams inflate to all the voxels), ending
/// as its format does. Throws repose::WriteFailure naming target otherwise.
void VerifyStaged(const std::string& target, const ImageFormat& format, const Staging& staging,
  std::uintmax_t voxelBytes)
{
  const std::string file = staging.file.string();
  if (!fs::exists(staging.file))
  {
    repose::throwWriteFailure(target, file, errno);
  }
  if (format.gzipNifti)
  {
    repose::requireCompleteGzip(target, file, voxelBytes);
  }
  else if (format.compress)
  {
    RequireCompleteData(target, file, voxelBytes);
  }
  repose::requireWritten(target, format.pair ? staging.folder.string() : file, 1);
  if (format.vti)
  {
    repose::requireEndsWith(target, file, "</VTKFile>\n");
  }
  else if (!format.compress && DataBytes(format.pair ? staging.folder : staging.file) < voxelBytes)
  {
    repose::throwWriteFailure(target, file);
  }
}

/// The staged files moved to the target's folder, the temporary folder removed.
void MoveOut(const Staging& staging)
{
  for (const auto& entry : fs::directory_iterator(staging.folder))
  {
    fs::rename(entry.path(), staging.dir / entry.path().filename());
  }
  fs::remove(staging.folder);
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
  if (target.empty())
  {
    return this->Fail("no file name set");
  }
  if (!given || !given->GetPointData()->GetScalars() || given->GetNumberOfPoints() < 1)
  {
    return this->Fail("input has no image scalars");
  }
  const vtkSmartPointer<vtkImageData> input =
    this->SmallestIntegerType ? WithSmallestIntegerType(given) : vtkSmartPointer<vtkImageData>(given);
  const int components = input->GetPointData()->GetScalars()->GetNumberOfComponents();
  if (components != 1 && !(components == 3 && input->GetScalarType() == VTK_FLOAT))
  {
    return this->Fail("input scalars must have one component (or three floats: a vector field)");
  }
  const ImageFormat format = FormatOf(target);
  if (!(format.compress || format.pair || format.vti || format.nifti))
  {
    return this->Fail("unknown extension; use .nii, .nii.gz, .nrrd, .nhdr, .mha, .mhd or .vti");
  }
  repose_vtk::RegisterItkImageFactories();
  Staging staging;
  const std::string notStaged = Stage(target, staging);
  if (!notStaged.empty())
  {
    return this->Fail(notStaged);
  }
  const std::uintmax_t voxelBytes = std::uintmax_t(input->GetNumberOfPoints()) *
    std::uintmax_t(input->GetScalarSize()) * std::uintmax_t(components);
  std::error_code ec;
  try
  {
    errno = 0;
    if (format.vti)
    {
      WriteVti(input, staging.file.string());
    }
    else
    {
      WriteItkStaged(input, target, format, staging, voxelBytes, this->HeaderFields(input),
        this->Description ? this->Description
          : components == 3 ? "displacement field"
          : this->SmallestIntegerType ? "labels"
                                      : "image");
    }
    VerifyStaged(target, format, staging, voxelBytes);
    MoveOut(staging);
  }
  catch (const repose::WriteFailure& e)
  {
    fs::remove_all(staging.folder, ec);
    return this->Fail(e.reason);
  }
  catch (const itk::ExceptionObject& e)
  {
    // ITK's description runs over lines and names the temporary file: the cause, when known, says more.
    const int err = errno;
    const std::string known =
      repose::knownWriteFailure(staging.file.string(), repose::isStorageError(err) ? err : 0);
    fs::remove_all(staging.folder, ec);
    return this->Fail(known.empty() ? e.GetDescription() : known);
  }
  catch (const std::exception& e)
  {
    fs::remove_all(staging.folder, ec);
    return this->Fail(e.what());
  }
  return 1;
}

void vtkReposeImageWriter::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "SmallestIntegerType: " << this->SmallestIntegerType << "\n";
  os << indent << "Description: " << (this->Description ? this->Description : "(from the content)") << "\n";
}
