#include "vtkReposeSlicerSegmentationWriter.h"

#include "vtkImageData.h"
#include "vtkObjectFactory.h"

#include "slicer_segmentation.h"

#include <algorithm>
#include <cctype>
#include <stdexcept>

vtkStandardNewMacro(vtkReposeSlicerSegmentationWriter);

vtkReposeSlicerSegmentationWriter::vtkReposeSlicerSegmentationWriter()
{
  this->SmallestIntegerType = true;
}

vtkReposeSlicerSegmentationWriter::~vtkReposeSlicerSegmentationWriter() = default;

void vtkReposeSlicerSegmentationWriter::AddSegment(int value, const char* name, double r, double g, double b)
{
  this->Segments.push_back({ value, name ? name : "", { r, g, b } });
  this->Modified();
}

void vtkReposeSlicerSegmentationWriter::RemoveAllSegments()
{
  this->Segments.clear();
  this->Modified();
}

int vtkReposeSlicerSegmentationWriter::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  std::string name = this->FileName ? this->FileName : "";
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return std::tolower(c); });
  if (name.size() < 5 || name.compare(name.size() - 5, 5, ".nrrd") != 0)
  {
    return this->Fail("a Slicer segmentation is a .seg.nrrd (or .nrrd) file");
  }
  return this->Superclass::RequestData(request, inputVector, outputVector);
}

std::vector<std::pair<std::string, std::string>> vtkReposeSlicerSegmentationWriter::HeaderFields(
  vtkImageData* written)
{
  std::vector<repose::SlicerSegment> segments;
  for (const Segment& s : this->Segments)
  {
    segments.push_back({ s.Value, s.Name, { s.Color[0], s.Color[1], s.Color[2] } });
  }
  if (written->GetScalarType() == VTK_FLOAT || written->GetScalarType() == VTK_DOUBLE)
  {
    throw std::runtime_error("a segmentation needs integer labels, not " +
      std::string(written->GetScalarTypeAsString()));
  }
  int dims[3];
  written->GetDimensions(dims);
  return repose::slicerSegmentationFields(segments, { dims[0], dims[1], dims[2] });
}

void vtkReposeSlicerSegmentationWriter::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Segments: " << this->Segments.size() << "\n";
}
