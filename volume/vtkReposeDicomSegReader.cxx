#include "vtkReposeDicomSegReader.h"

#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkStringArray.h"

#include "ReposeDicomSegmentation.h"

#include <stdexcept>

vtkStandardNewMacro(vtkReposeDicomSegReader);

struct vtkReposeDicomSegReader::Segments
{
  std::vector<repose::DicomSegment> List;
};

vtkReposeDicomSegReader::vtkReposeDicomSegReader()
  : Table(new Segments)
{
  this->SetNumberOfInputPorts(1);
  this->SetNumberOfOutputPorts(1);
}

vtkReposeDicomSegReader::~vtkReposeDicomSegReader()
{
  this->SetFileName(nullptr);
}

void vtkReposeDicomSegReader::AddSegment(int value, const char* name)
{
  repose::DicomSegment s;
  s.Value = value;
  s.Name = name ? name : "";
  this->Table->List.push_back(s);
  this->Modified();
}

void vtkReposeDicomSegReader::RemoveAllSegments()
{
  this->Table->List.clear();
  this->Modified();
}

int vtkReposeDicomSegReader::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkImageData");
  return 1;
}

int vtkReposeDicomSegReader::RequestInformation(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  // The reference's grid, int scalars.
  vtkInformation* in = inputVector[0]->GetInformationObject(0);
  vtkInformation* out = outputVector->GetInformationObject(0);
  out->CopyEntry(in, vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT());
  out->CopyEntry(in, vtkDataObject::ORIGIN());
  out->CopyEntry(in, vtkDataObject::SPACING());
  out->CopyEntry(in, vtkDataObject::DIRECTION());
  vtkDataObject::SetPointDataActiveScalarInfo(out, VTK_INT, 1);
  return 1;
}

int vtkReposeDicomSegReader::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkImageData* reference = vtkImageData::GetData(inputVector[0]);
  vtkImageData* output = vtkImageData::GetData(outputVector);
  this->LastError.clear();
  try
  {
    if (!this->FileName || !*this->FileName)
    {
      throw std::runtime_error("no file name set");
    }
    repose::LabelGrid grid = repose::LabelGridOf(reference, false);
    const std::vector<std::string> names = repose::ReadDicomSegmentation(this->FileName, this->Table->List, grid);
    auto labels = vtkSmartPointer<vtkIntArray>::New();
    labels->SetName("Labels");
    labels->SetNumberOfTuples(static_cast<vtkIdType>(grid.Values.size()));
    std::copy(grid.Values.begin(), grid.Values.end(), labels->GetPointer(0));
    output->CopyStructure(reference);
    output->GetPointData()->SetScalars(labels);
    auto segmentNames = vtkSmartPointer<vtkStringArray>::New();
    segmentNames->SetName("SegmentNames");
    for (const std::string& n : names)
    {
      segmentNames->InsertNextValue(n);
    }
    output->GetFieldData()->AddArray(segmentNames);
  }
  catch (const std::exception& e)
  {
    this->LastError = std::string(this->FileName ? this->FileName : "(no file name)") + ": cannot read (" + e.what() + ")";
    vtkErrorMacro(<< this->LastError);
    return 0;
  }
  return 1;
}

void vtkReposeDicomSegReader::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
}
