#include "vtkReposeDicomSegWriter.h"

#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkStringArray.h"

#include "ReposeDicomSegmentation.h"

#include <stdexcept>

vtkStandardNewMacro(vtkReposeDicomSegWriter);

struct vtkReposeDicomSegWriter::Segments
{
  std::vector<repose::DicomSegment> List;
};

vtkReposeDicomSegWriter::vtkReposeDicomSegWriter()
  : Table(new Segments)
{
}

vtkReposeDicomSegWriter::~vtkReposeDicomSegWriter()
{
  this->SetSeriesDescription(nullptr);
}

void vtkReposeDicomSegWriter::AddSegment(int value, const char* name, double r, double g, double b, bool bone)
{
  repose::DicomSegment s;
  s.Value = value;
  s.Name = name ? name : std::to_string(value);
  s.Colour = { r, g, b };
  s.Bone = bone;
  this->Table->List.push_back(s);
  this->Modified();
}

void vtkReposeDicomSegWriter::RemoveAllSegments()
{
  this->Table->List.clear();
  this->Modified();
}

int vtkReposeDicomSegWriter::RequestData(vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector*)
{
  vtkImageData* input = vtkImageData::GetData(inputVector[0]);
  if (!input || !input->GetPointData()->GetScalars() || input->GetNumberOfPoints() < 1)
  {
    return this->Fail("input has no label scalars");
  }
  const repose::DicomTags carried = repose::DicomTagsOf(input);
  const repose::LabelGrid labels = repose::LabelGridOf(input, true);
  const std::string description = this->SeriesDescription ? this->SeriesDescription : "";
  return this->WriteAtomically([&](const std::string& path) {
    repose::WriteDicomSegmentation(labels, this->Table->List, path, carried, description);
  });
}

void vtkReposeDicomSegWriter::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Segments: " << this->Table->List.size() << "\n";
}
