#include "vtkReposeDicomSegWriter.h"

#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkStringArray.h"

#include "ReposeDicomSegmentation.h"

#include <filesystem>
#include <stdexcept>
#include <unistd.h>

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
  const std::string target = this->FileName ? this->FileName : "";
  auto fail = [this](const std::string& reason) { return this->Fail(reason); };
  if (target.empty())
  {
    return fail("no file name set");
  }
  if (!input || !input->GetPointData()->GetScalars() || input->GetNumberOfPoints() < 1)
  {
    return fail("input has no label scalars");
  }
  repose::DicomTags carried;
  auto* tags = vtkStringArray::SafeDownCast(input->GetFieldData()->GetAbstractArray("DicomTags"));
  for (vtkIdType i = 0; tags && i < tags->GetNumberOfValues(); ++i)
  {
    const std::string entry = tags->GetValue(i);
    if (entry.size() > 10 && entry[4] == '|' && entry[9] == '=')
    {
      carried.emplace_back(entry.substr(0, 9), entry.substr(10));
    }
  }
  const std::filesystem::path finalPath(target);
  const std::filesystem::path temporary = finalPath.parent_path() /
    ("." + finalPath.filename().string() + ".tmp-" + std::to_string(::getpid()));
  std::error_code ignored;
  try
  {
    repose::WriteDicomSegmentation(repose::LabelGridOf(input, true), this->Table->List, temporary.string(), carried,
      this->SeriesDescription ? this->SeriesDescription : "");
    std::filesystem::rename(temporary, finalPath);
  }
  catch (const std::exception& e)
  {
    std::filesystem::remove(temporary, ignored);
    return fail(e.what());
  }
  return 1;
}

void vtkReposeDicomSegWriter::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Segments: " << this->Table->List.size() << "\n";
}
