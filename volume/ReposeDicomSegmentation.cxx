#include "ReposeDicomSegmentation.h"

#include "repose_version.h"

#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkMatrix3x3.h"
#include "vtkPointData.h"

#include "dcmtk/config/osconfig.h" // DCMTK's configuration before any of its headers

#include "dcmtk/dcmdata/dcuid.h"
#include "dcmtk/oflog/oflog.h"
#include "dcmtk/dcmfg/fgfracon.h"
#include "dcmtk/dcmfg/fgpixmsr.h"
#include "dcmtk/dcmfg/fgplanor.h"
#include "dcmtk/dcmfg/fgplanpo.h"
#include "dcmtk/dcmfg/fgseg.h"
#include "dcmtk/dcmiod/cielabutil.h"
#include "dcmtk/dcmseg/segdoc.h"
#include "dcmtk/dcmseg/segment.h"
#include "dcmtk/dcmseg/segutils.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <stdexcept>

namespace repose
{
namespace
{

void Check(const OFCondition& c, const std::string& what)
{
  if (c.bad())
  {
    throw std::runtime_error(what + ": " + c.text());
  }
}

std::string Text(double x)
{
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.10g", x);
  return buffer;
}

// DCMTK logs its checks' remarks on the console; failures come back as conditions, reported here.
void QuietDcmtk()
{
  static const bool once = [] {
    OFLog::configure(OFLogger::ERROR_LOG_LEVEL);
    return true;
  }();
  (void)once;
}

std::string Uid()
{
  char uid[100];
  return dcmGenerateUniqueIdentifier(uid, SITE_INSTANCE_UID_ROOT);
}

std::string Carried(const DicomTags& carried, const std::string& key)
{
  for (const auto& [k, v] : carried)
  {
    if (k == key)
    {
      return v;
    }
  }
  return "";
}

// Where voxel (i, j, k) of the grid is, in the patient frame (mm, LPS).
std::array<double, 3> At(const LabelGrid& g, double i, double j, double k)
{
  const double ijk[3] = { i * g.Spacing[0], j * g.Spacing[1], k * g.Spacing[2] };
  std::array<double, 3> p = g.Origin;
  for (int r = 0; r < 3; ++r)
  {
    for (int c = 0; c < 3; ++c)
    {
      p[std::size_t(r)] += g.Direction[std::size_t(3 * r + c)] * ijk[c];
    }
  }
  return p;
}

} // namespace

LabelGrid LabelGridOf(vtkImageData* image, bool withValues)
{
  LabelGrid g;
  int extent[6];
  image->GetExtent(extent);
  for (int a = 0; a < 3; ++a)
  {
    g.Dims[std::size_t(a)] = extent[2 * a + 1] - extent[2 * a] + 1;
    g.Spacing[std::size_t(a)] = image->GetSpacing()[a];
  }
  double first[3];
  image->TransformIndexToPhysicalPoint(extent[0], extent[2], extent[4], first);
  g.Origin = { first[0], first[1], first[2] };
  for (int i = 0; i < 9; ++i)
  {
    g.Direction[std::size_t(i)] = image->GetDirectionMatrix()->GetData()[i];
  }
  vtkDataArray* scalars = image->GetPointData()->GetScalars();
  if (withValues && scalars)
  {
    g.Values.resize(std::size_t(scalars->GetNumberOfTuples()));
    for (vtkIdType i = 0; i < scalars->GetNumberOfTuples(); ++i)
    {
      g.Values[std::size_t(i)] = int(std::lround(scalars->GetTuple1(i)));
    }
  }
  return g;
}

void WriteDicomSegmentation(const LabelGrid& labels, const std::vector<DicomSegment>& segments,
  const std::string& path, const DicomTags& carried, const std::string& description)
{
  const int nx = labels.Dims[0], ny = labels.Dims[1], nz = labels.Dims[2];
  if (nx < 1 || ny < 1 || nz < 1 || nx > 65535 || ny > 65535 ||
    labels.Values.size() != std::size_t(nx) * std::size_t(ny) * std::size_t(nz))
  {
    throw std::runtime_error("label grid does not fit a DICOM segmentation");
  }
  QuietDcmtk();
  DcmSegmentation* created = nullptr;
  Check(DcmSegmentation::createBinarySegmentation(created, Uint16(ny), Uint16(nx),
          IODGeneralEquipmentModule::EquipmentInfo("Repose", "repose", "0", REPOSE_VERSION),
          ContentIdentificationMacro("1", "REPOSED", description.substr(0, 64).c_str(), "")),
    "creating the segmentation");
  std::unique_ptr<DcmSegmentation> seg(created);

  // Patient, study and frame of reference: the CT's when known, so viewers put the two together.
  const std::string study = Carried(carried, "0020|000d"), frame = Carried(carried, "0020|0052");
  Check(seg->getPatient().setPatientName(Carried(carried, "0010|0010").empty() ? "ANONYMOUS"
                                                                               : Carried(carried, "0010|0010").c_str()),
    "patient name");
  Check(seg->getPatient().setPatientID(Carried(carried, "0010|0020").c_str()), "patient ID");
  Check(seg->getStudy().setStudyInstanceUID(study.empty() ? Uid().c_str() : study.c_str()), "study UID");
  if (!Carried(carried, "0008|0020").empty())
  {
    seg->getStudy().setStudyDate(Carried(carried, "0008|0020").c_str());
    seg->getStudy().setStudyTime(Carried(carried, "0008|0030").c_str());
  }
  Check(seg->getFrameOfReference().setFrameOfReferenceUID(frame.empty() ? Uid().c_str() : frame.c_str()),
    "frame of reference UID");
  seg->getSeries().setSeriesDescription(description.substr(0, 64).c_str());
  seg->getSeries().setSeriesNumber("1002");

  // Frames are ordered by segment, then slice: the dimensions say so.
  const std::string dimensions = Uid();
  Check(seg->getDimensions().addDimensionIndex(
          DCM_ReferencedSegmentNumber, dimensions.c_str(), DCM_SegmentIdentificationSequence, "Segment"),
    "dimension index");
  Check(seg->getDimensions().addDimensionIndex(
          DCM_ImagePositionPatient, dimensions.c_str(), DCM_PlanePositionSequence, "Position"),
    "dimension index");
  const auto& d = labels.Direction;
  std::unique_ptr<FGPlaneOrientationPatient> orientation(FGPlaneOrientationPatient::createMinimal(
    Text(d[0]).c_str(), Text(d[3]).c_str(), Text(d[6]).c_str(), Text(d[1]).c_str(), Text(d[4]).c_str(),
    Text(d[7]).c_str()));
  Check(seg->addForAllFrames(*orientation), "plane orientation");
  FGPixelMeasures measures;
  Check(measures.setPixelSpacing((Text(labels.Spacing[1]) + "\\" + Text(labels.Spacing[0])).c_str()), "spacing");
  Check(measures.setSliceThickness(Text(labels.Spacing[2]).c_str()), "slice thickness");
  Check(measures.setSpacingBetweenSlices(Text(labels.Spacing[2]).c_str()), "slice spacing");
  Check(seg->addForAllFrames(measures), "pixel measures");

  const std::size_t sliceSize = std::size_t(nx) * std::size_t(ny);
  std::vector<Uint8> mask(sliceSize);
  std::unique_ptr<FGPlanePosPatient> position(FGPlanePosPatient::createMinimal("0", "0", "0"));
  FGFrameContent content;
  OFVector<FGBase*> perFrame;
  perFrame.push_back(position.get());
  perFrame.push_back(&content);
  for (const DicomSegment& s : segments)
  {
    if (std::find(labels.Values.begin(), labels.Values.end(), s.Value) == labels.Values.end())
    {
      continue;
    }
    DcmSegment* segment = nullptr;
    // Category and type: SNOMED CT "Tissue" (85756007); bones "Bone structure" (272673000).
    Check(DcmSegment::create(segment, s.Name.substr(0, 64).c_str(), CodeSequenceMacro("85756007", "SCT", "Tissue"),
            s.Bone ? CodeSequenceMacro("272673000", "SCT", "Bone") : CodeSequenceMacro("85756007", "SCT", "Tissue"),
            DcmSegTypes::SAT_AUTOMATIC, "Repose"),
      "segment " + s.Name);
    double L, a, b;
    IODCIELabUtil::rgb2DicomLab(L, a, b, s.Colour[0], s.Colour[1], s.Colour[2]);
    segment->setRecommendedDisplayCIELabValue(Uint16(std::lround(L)), Uint16(std::lround(a)), Uint16(std::lround(b)));
    Uint16 number = 0;
    const OFCondition added = seg->addSegment(segment, number);
    if (added.bad())
    {
      delete segment;
      Check(added, "segment " + s.Name);
    }
    for (int k = 0; k < nz; ++k)
    {
      const int* slice = labels.Values.data() + std::size_t(k) * sliceSize;
      bool any = false;
      for (std::size_t i = 0; i < sliceSize; ++i)
      {
        mask[i] = slice[i] == s.Value ? 1 : 0;
        any = any || mask[i];
      }
      if (!any)
      {
        continue;
      }
      const auto p = At(labels, 0, 0, k);
      Check(position->setImagePositionPatient(Text(p[0]).c_str(), Text(p[1]).c_str(), Text(p[2]).c_str()), "position");
      Check(content.setDimensionIndexValues(number, 0), "frame content");
      Check(content.setDimensionIndexValues(Uint32(k + 1), 1), "frame content");
      Check(seg->addFrame(mask.data(), number, perFrame), "frame of " + s.Name);
    }
  }
  if (seg->getNumberOfFrames() == 0)
  {
    throw std::runtime_error("no label of the table is in the volume");
  }
  Check(seg->saveFile(path.c_str()), "writing");
}

std::vector<std::string> ReadDicomSegmentation(
  const std::string& path, const std::vector<DicomSegment>& segments, LabelGrid& grid)
{
  QuietDcmtk();
  DcmSegmentation* loaded = nullptr;
  Check(DcmSegmentation::loadFile(path.c_str(), loaded), "reading");
  std::unique_ptr<DcmSegmentation> seg(loaded);
  const Uint16 rows = Uint16(grid.Dims[1]), columns = Uint16(grid.Dims[0]);
  std::vector<std::string> names;
  std::map<Uint16, int> valueOf;
  for (Uint16 n = 1; seg->getSegment(n); ++n)
  {
    OFString label;
    seg->getSegment(n)->getSegmentLabel(label);
    names.emplace_back(label.c_str());
    valueOf[n] = n;
    for (const DicomSegment& s : segments)
    {
      if (s.Name == label.c_str())
      {
        valueOf[n] = s.Value;
      }
    }
  }
  const std::size_t sliceSize = std::size_t(grid.Dims[0]) * std::size_t(grid.Dims[1]);
  grid.Values.assign(sliceSize * std::size_t(grid.Dims[2]), 0);
  FGInterface& groups = seg->getFunctionalGroups();
  for (std::size_t f = 0; f < seg->getNumberOfFrames(); ++f)
  {
    auto* position = dynamic_cast<FGPlanePosPatient*>(groups.get(Uint32(f), DcmFGTypes::EFG_PLANEPOSPATIENT));
    auto* identification = dynamic_cast<FGSegmentation*>(groups.get(Uint32(f), DcmFGTypes::EFG_SEGMENTATION));
    Float64 x = 0, y = 0, z = 0;
    Uint16 number = 0;
    if (!position || !identification || position->getImagePositionPatient(x, y, z).bad() ||
      identification->getReferencedSegmentNumber(number).bad())
    {
      throw std::runtime_error("frame " + std::to_string(f + 1) + " has no position or segment");
    }
    // The frame's index on the grid: its first pixel must be a voxel (i = j = 0) of slice k.
    const double rel[3] = { x - grid.Origin[0], y - grid.Origin[1], z - grid.Origin[2] };
    double ijk[3];
    for (int c = 0; c < 3; ++c)
    {
      ijk[c] = 0;
      for (int r = 0; r < 3; ++r)
      {
        ijk[c] += grid.Direction[std::size_t(3 * r + c)] * rel[r];
      }
      ijk[c] /= grid.Spacing[std::size_t(c)];
    }
    const long k = std::lround(ijk[2]);
    if (std::abs(ijk[0]) > 1e-3 || std::abs(ijk[1]) > 1e-3 || std::abs(ijk[2] - double(k)) > 1e-3 || k < 0 ||
      k >= grid.Dims[2])
    {
      throw std::runtime_error("frame " + std::to_string(f + 1) + " is not a slice of the grid");
    }
    const DcmIODTypes::Frame* packed = seg->getFrame(f);
    if (!packed || packed->length != (std::size_t(rows) * columns + 7) / 8)
    {
      throw std::runtime_error("frame " + std::to_string(f + 1) + " is not the size of the grid's slices");
    }
    std::unique_ptr<DcmIODTypes::Frame> bits(DcmSegUtils::unpackBinaryFrame(packed, rows, columns));
    if (!bits)
    {
      throw std::runtime_error("frame " + std::to_string(f + 1) + " cannot be unpacked");
    }
    int* slice = grid.Values.data() + std::size_t(k) * sliceSize;
    for (std::size_t i = 0; i < sliceSize; ++i)
    {
      if (bits->pixData[i])
      {
        slice[i] = valueOf[number];
      }
    }
  }
  return names;
}

} // namespace repose
