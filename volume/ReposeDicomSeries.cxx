#include "ReposeDicomSeries.h"

#include "dicom_slice_stack.h"

#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkStringArray.h"

#include "gdcmUIDGenerator.h"
#include "itkGDCMImageIO.h"
#include "itkGDCMSeriesFileNames.h"
#include "itkImageFileWriter.h"
#include "itkImageRegionConstIterator.h"
#include "itkImageSeriesReader.h"
#include "itkMetaDataObject.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>

namespace repose
{
namespace
{
namespace fs = std::filesystem;
using Volume = itk::Image<float, 3>;

// Who the patient is and which study: kept on a series derived from this one.
const char* const kPatientAndStudyTags[] = { "0010|0010", "0010|0020", "0010|0030", "0010|0040", "0020|000d",
  "0008|0020", "0008|0030", "0008|0050", "0020|0010", "0008|0090", "0008|1030", "0018|5100", "0020|0052" };

std::string Tag(const itk::MetaDataDictionary& d, const std::string& key)
{
  std::string value;
  itk::ExposeMetaData<std::string>(d, key, value);
  while (!value.empty() && (value.back() == ' ' || value.back() == '\0'))
  {
    value.pop_back();
  }
  return value;
}

std::vector<double> Numbers(const std::string& text)
{
  std::vector<double> values;
  std::string part;
  std::istringstream in(text);
  while (std::getline(in, part, '\\'))
  {
    try
    {
      values.push_back(std::stod(part));
    }
    catch (const std::exception&)
    {
      return {};
    }
  }
  return values;
}

std::string Text(double x)
{
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.6g", x);
  return buffer;
}

// A series' Series Instance UID and description, from its first file's header.
struct SeriesLabel
{
  std::string UID, Description;
};

SeriesLabel LabelOf(const std::string& file)
{
  auto io = itk::GDCMImageIO::New();
  io->SetFileName(file);
  SeriesLabel label;
  try
  {
    io->ReadImageInformation();
    io->GetValueFromTag("0020|000e", label.UID);
    io->GetValueFromTag("0008|103e", label.Description);
  }
  catch (const itk::ExceptionObject&)
  {
  }
  for (std::string* text : { &label.UID, &label.Description })
  {
    while (!text->empty() && (text->back() == ' ' || text->back() == '\0'))
    {
      text->pop_back();
    }
  }
  return label;
}

// The chosen series' file names; a one-line error naming what the folder holds otherwise.
std::vector<std::string> SeriesFiles(const std::string& folder, const std::string& wanted, std::string& uid)
{
  auto names = itk::GDCMSeriesFileNames::New();
  names->SetUseSeriesDetails(true); // a localizer or a second reconstruction is a series of its own
  names->SetGlobalWarningDisplay(false);
  names->SetDirectory(folder);
  const std::vector<std::string> uids = names->GetSeriesUIDs();
  if (uids.empty())
  {
    throw std::runtime_error("no DICOM series in this folder");
  }
  // With series details the identifiers are the Series Instance UID followed by other attributes:
  // a series is chosen by its Series Instance UID (or that identifier).
  std::vector<std::string> matches;
  std::string list;
  for (const std::string& u : uids)
  {
    const std::vector<std::string> files = names->GetFileNames(u);
    const SeriesLabel label = LabelOf(files.front());
    if (wanted.empty() || u == wanted || label.UID == wanted)
    {
      matches.push_back(u);
    }
    list += (list.empty() ? "" : ", ") + (label.UID.empty() ? u : label.UID) +
      (label.Description.empty() ? "" : " '" + label.Description + "'") + " (" + std::to_string(files.size()) +
      " files)";
  }
  if (matches.size() != 1)
  {
    throw std::runtime_error(wanted.empty()
        ? std::to_string(uids.size()) + " DICOM series in this folder, choose one with --series-uid: " + list
        : "no single DICOM series " + wanted + " in this folder (it holds " + list + ")");
  }
  uid = matches.front();
  return names->GetFileNames(uid);
}

} // namespace

DicomTags DicomTagsOf(vtkImageData* image)
{
  DicomTags tags;
  auto* array = vtkStringArray::SafeDownCast(image->GetFieldData()->GetAbstractArray("DicomTags"));
  for (vtkIdType i = 0; array && i < array->GetNumberOfValues(); ++i)
  {
    const std::string entry = array->GetValue(i);
    if (entry.size() > 10 && entry[4] == '|' && entry[9] == '=')
    {
      tags.emplace_back(entry.substr(0, 9), entry.substr(10));
    }
  }
  return tags;
}

DicomSeriesVolume ReadDicomSeries(const std::string& folder, const std::string& seriesUID)
{
  std::string uid;
  const std::vector<std::string> files = SeriesFiles(folder, seriesUID, uid);
  auto io = itk::GDCMImageIO::New();
  auto reader = itk::ImageSeriesReader<Volume>::New();
  reader->SetImageIO(io);
  reader->SetFileNames(files);
  reader->SetGlobalWarningDisplay(false);
  // The slice headers' sizes, checked before any voxel is allocated (a damaged header can claim rows
  // and columns enough for gigabytes per slice).
  reader->UpdateOutputInformation();
  double voxels = 1.0;
  for (unsigned a = 0; a < 3; ++a)
  {
    voxels *= double(reader->GetOutput()->GetLargestPossibleRegion().GetSize()[a]);
  }
  if (!(voxels >= 1.0 && voxels <= 4294967295.0))
  {
    throw std::runtime_error("DICOM series claims " + Text(voxels) + " voxels");
  }
  reader->Update();
  DicomSeriesVolume out;
  out.Image = reader->GetOutput();
  const auto* dictionaries = reader->GetMetaDataDictionaryArray();
  if (!dictionaries || dictionaries->size() != files.size())
  {
    throw std::runtime_error("DICOM series: per-slice attributes are missing");
  }
  std::vector<DicomSlice> slices(files.size());
  for (std::size_t k = 0; k < files.size(); ++k)
  {
    const std::vector<double> p = Numbers(Tag(*(*dictionaries)[k], "0020|0032"));
    const std::vector<double> o = Numbers(Tag(*(*dictionaries)[k], "0020|0037"));
    if (p.size() != 3 || o.size() != 6)
    {
      throw std::runtime_error(fs::path(files[k]).filename().string() +
        ": no ImagePositionPatient / ImageOrientationPatient (not a cross-sectional image)");
    }
    std::copy(p.begin(), p.end(), slices[k].position.begin());
    std::copy(o.begin(), o.end(), slices[k].orientation.begin());
  }
  const auto spacing = out.Image->GetSpacing();
  const SliceStackGeometry stack = checkSliceStack(slices, std::min(spacing[0], spacing[1]));
  if (files.size() > 1)
  {
    // ITK's spacing along k from the same positions; its direction's third column is the stacking
    // direction, which for a grid is the normal (or its opposite).
    auto s = spacing;
    s[2] = stack.sliceSpacing;
    out.Image->SetSpacing(s);
  }
  out.SeriesUID = Tag(*(*dictionaries)[0], "0020|000e");
  for (const char* key : kPatientAndStudyTags)
  {
    const std::string value = Tag(*(*dictionaries)[0], key);
    if (!value.empty())
    {
      out.PatientAndStudy.emplace_back(key, value);
    }
  }
  return out;
}

void WriteDicomSeries(const Volume* image, const std::string& folder, const DicomTags& carried,
  const std::string& description)
{
  if (fs::exists(folder))
  {
    throw std::runtime_error("DICOM output folder exists already");
  }
  fs::create_directories(folder);
  try
  {
    gdcm::UIDGenerator uids;
    const std::string seriesUID = uids.Generate();
    std::string studyUID;
    itk::MetaDataDictionary base;
    bool frameOfReference = false; // one for the whole series: its slices share a patient frame
    for (const auto& [key, value] : carried)
    {
      itk::EncapsulateMetaData<std::string>(base, key, value);
      studyUID = key == "0020|000d" ? value : studyUID;
      frameOfReference = frameOfReference || key == "0020|0052";
    }
    if (!frameOfReference)
    {
      itk::EncapsulateMetaData<std::string>(base, "0020|0052", uids.Generate());
    }
    if (studyUID.empty())
    {
      itk::EncapsulateMetaData<std::string>(base, "0020|000d", uids.Generate());
      itk::EncapsulateMetaData<std::string>(base, "0010|0010", "ANONYMOUS");
      itk::EncapsulateMetaData<std::string>(base, "0010|0020", "ANONYMOUS");
    }
    itk::EncapsulateMetaData<std::string>(base, "0020|000e", seriesUID);
    itk::EncapsulateMetaData<std::string>(base, "0008|0060", "CT");
    itk::EncapsulateMetaData<std::string>(base, "0008|0008", "DERIVED\\SECONDARY");
    itk::EncapsulateMetaData<std::string>(base, "0008|103e", description.substr(0, 64));
    itk::EncapsulateMetaData<std::string>(base, "0020|0011", "1001");

    using Slice = itk::Image<short, 3>;
    const auto region = image->GetLargestPossibleRegion();
    const auto size = region.GetSize();
    const auto direction = image->GetDirection();
    const auto spacing = image->GetSpacing();
    for (unsigned k = 0; k < size[2]; ++k)
    {
      // One slice as a one-voxel-thick volume: GDCM writes its position, orientation and spacing
      // from the slice's own geometry.
      auto slice = Slice::New();
      Slice::RegionType r;
      r.SetSize({ { size[0], size[1], 1 } });
      slice->SetRegions(r);
      slice->Allocate();
      itk::Index<3> corner = { { 0, 0, static_cast<itk::IndexValueType>(k) } };
      itk::Point<double, 3> origin;
      image->TransformIndexToPhysicalPoint(corner, origin);
      slice->SetOrigin(origin);
      slice->SetSpacing(spacing);
      slice->SetDirection(direction);
      short* to = slice->GetBufferPointer();
      const float* from = image->GetBufferPointer() + static_cast<std::size_t>(k) * size[0] * size[1];
      for (std::size_t i = 0, n = size[0] * size[1]; i < n; ++i)
      {
        const float v = std::isfinite(from[i]) ? from[i] : -1024.0f;
        to[i] = static_cast<short>(std::lround(std::clamp(v, -32768.0f, 32767.0f)));
      }
      itk::MetaDataDictionary d = base;
      itk::EncapsulateMetaData<std::string>(d, "0008|0018", uids.Generate());
      itk::EncapsulateMetaData<std::string>(d, "0020|0013", std::to_string(k + 1));
      itk::EncapsulateMetaData<std::string>(d, "0018|0050", Text(spacing[2]));
      slice->SetMetaDataDictionary(d);
      auto io = itk::GDCMImageIO::New();
      io->KeepOriginalUIDOn(); // the UIDs above: one series, one instance per file
      auto writer = itk::ImageFileWriter<Slice>::New();
      writer->SetImageIO(io);
      char name[32];
      std::snprintf(name, sizeof(name), "IM%05u.dcm", k + 1);
      writer->SetFileName((fs::path(folder) / name).string());
      writer->SetInput(slice);
      writer->Update();
    }
  }
  catch (...)
  {
    std::error_code ignored;
    fs::remove_all(folder, ignored);
    throw;
  }
}

} // namespace repose
