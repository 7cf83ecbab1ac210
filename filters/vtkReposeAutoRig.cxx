#include "vtkReposeAutoRig.h"

#include "ReposeImageConversion.h"

#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkMatrix3x3.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"

#include "auto_rig.h"
#include "label_table.h"
#include "skeleton.h"
#include "array_names.h"

#include <algorithm>
#include <exception>

vtkStandardNewMacro(vtkReposeAutoRig);

vtkReposeAutoRig::vtkReposeAutoRig()
{
  this->SetNumberOfInputPorts(1);
  this->SetNumberOfOutputPorts(1);
}

int vtkReposeAutoRig::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  this->SkeletonJSON.clear();
  this->Report.clear();
  this->OutputLabelTableTSV.clear();
  this->NumberOfJoints = 0;
  this->NumberOfReassignedFragments = 0;
  this->ReassignedFragmentVoxels = this->UnassignedFragmentVoxels = 0;
  vtkImageData* input = vtkImageData::GetData(inputVector[0]);
  vtkImageData* output = vtkImageData::GetData(outputVector);
  vtkDataArray* scalars = input ? input->GetPointData()->GetScalars() : nullptr;
  if (!scalars || scalars->GetNumberOfComponents() != 1 || !output)
  {
    vtkErrorMacro("the label image (input 0) has no single-component scalars");
    return 0;
  }
  try
  {
    repose::LabelVolume labels;
    if (!repose_vtk::ToVolume(input, labels))
    {
      vtkErrorMacro("the label image's scalars do not match its extent");
      return 0;
    }
    repose::LabelTable table = this->LabelTableTSV.empty()
      ? repose::builtinTotalSegmentatorTable()
      : repose::parseLabelTable(
          this->LabelTableTSV, this->LabelTableName.empty() ? "LabelTableTSV" : this->LabelTableName);
    if (!this->LabelTableName.empty()) table.source = this->LabelTableName;
    repose::AutoRigOptions options;
    options.maxGapMm = this->MaxGapMm;
    options.maxGapVoxels = this->MaxGapVoxels;
    options.checkTable = this->CheckLabelTable;
    const repose::AutoRigResult result = repose::autoRig(labels, table, options);

    output->CopyStructure(input);
    vtkNew<vtkIntArray> values;
    values->SetName(scalars->GetName() ? scalars->GetName() : repose::arrays::kLabels);
    values->SetNumberOfTuples(static_cast<vtkIdType>(result.labels.data.size()));
    std::copy(result.labels.data.begin(), result.labels.data.end(), values->GetPointer(0));
    output->GetPointData()->SetScalars(values);

    this->SkeletonJSON = repose::skeletonToJson(result.skeleton);
    this->Report = result.report.text();
    this->OutputLabelTableTSV = repose::labelTableToTsv(result.table);
    this->NumberOfJoints = static_cast<int>(result.skeleton.size());
    this->Seconds = result.report.seconds;
    this->NumberOfReassignedFragments = static_cast<int>(result.report.fragmentsReassigned);
    this->ReassignedFragmentVoxels = static_cast<vtkIdType>(result.report.fragmentVoxelsReassigned);
    this->UnassignedFragmentVoxels = static_cast<vtkIdType>(result.report.noiseVoxels);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  return 1;
}

void vtkReposeAutoRig::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "LabelTableTSV: " << (this->LabelTableTSV.empty() ? "(TotalSegmentator)" : "(given)") << "\n";
  os << indent << "LabelTableName: " << this->LabelTableName << "\n";
  os << indent << "CheckLabelTable: " << this->CheckLabelTable << "\n";
  os << indent << "MaxGapMm: " << this->MaxGapMm << "\n";
  os << indent << "MaxGapVoxels: " << this->MaxGapVoxels << "\n";
  os << indent << "NumberOfJoints: " << this->NumberOfJoints << "\n";
}
