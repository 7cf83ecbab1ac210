#include "vtkReposePhantomSource.h"

#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkStreamingDemandDrivenPipeline.h"

#include "ReposeImageConversion.h"
#include "phantom.h"
#include "skeleton.h"
#include "array_names.h"

#include <algorithm>
#include <exception>
#include <set>
#include <sstream>

vtkStandardNewMacro(vtkReposePhantomSource);

namespace
{
repose::PhantomSize ToCore(int size)
{
  switch (size)
  {
    case vtkReposePhantomSource::SMALL:
      return repose::PhantomSize::Small;
    case vtkReposePhantomSource::MEDIUM:
      return repose::PhantomSize::Medium;
    case vtkReposePhantomSource::LARGE:
      return repose::PhantomSize::Large;
    default:
      return repose::PhantomSize::Tiny;
  }
}

repose::PhantomRestPose ToCoreRestPose(int rest)
{
  return rest == vtkReposePhantomSource::CONTACT ? repose::PhantomRestPose::Contact
                                                 : repose::PhantomRestPose::Apart;
}

}

vtkReposePhantomSource::vtkReposePhantomSource()
{
  this->SetNumberOfInputPorts(0);
  this->SetNumberOfOutputPorts(1);
}

void vtkReposePhantomSource::SetSizeName(const char* name)
{
  try
  {
    this->SetSize(static_cast<int>(repose::parsePhantomSize(name ? name : "")));
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
  }
}

const char* vtkReposePhantomSource::GetSizeName()
{
  static const char* const names[] = { "tiny", "small", "medium", "large" };
  return names[std::clamp(this->Size, static_cast<int>(TINY), static_cast<int>(LARGE))];
}

void vtkReposePhantomSource::SetRestPoseName(const char* name)
{
  try
  {
    this->SetRestPose(static_cast<int>(repose::parsePhantomRestPose(name ? name : "")));
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
  }
}

const char* vtkReposePhantomSource::GetRestPoseName()
{
  return this->RestPose == CONTACT ? "contact" : "apart";
}

const char* vtkReposePhantomSource::GetSkeletonJSON()
{
  try
  {
    this->SkeletonJSON = repose::skeletonToJson(repose::describePhantom(ToCore(this->Size), ToCoreRestPose(this->RestPose)).skeleton);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    this->SkeletonJSON.clear();
  }
  return this->SkeletonJSON.c_str();
}

const char* vtkReposePhantomSource::GetLabelTableTSV()
{
  const repose::Phantom ph = repose::describePhantom(ToCore(this->Size), ToCoreRestPose(this->RestPose));
  std::set<int> bones;
  for (const repose::Joint& joint : ph.skeleton.joints)
  {
    bones.insert(joint.labels.begin(), joint.labels.end());
  }
  std::ostringstream out;
  out << "value\tname\tkind\n";
  for (const auto& entry : ph.labelNames)
  {
    out << entry.first << '\t' << entry.second << '\t' << (bones.count(entry.first) ? "bone" : "soft")
        << '\n';
  }
  this->LabelTableTSV = out.str();
  return this->LabelTableTSV.c_str();
}

int vtkReposePhantomSource::RequestInformation(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  try
  {
    repose_vtk::SetOutputGeometry(repose::describePhantom(ToCore(this->Size), ToCoreRestPose(this->RestPose)).labels.grid,
      outputVector->GetInformationObject(0), VTK_INT);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  return 1;
}

int vtkReposePhantomSource::RequestData(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  vtkImageData* output = vtkImageData::GetData(outInfo);
  if (!output)
  {
    vtkErrorMacro(<< "no image output");
    return 0;
  }
  try
  {
    const repose::Phantom ph = repose::makePhantom(ToCore(this->Size), ToCoreRestPose(this->RestPose));
    const repose::ImageGrid& grid = ph.labels.grid;
    output->Initialize();
    output->SetExtent(0, grid.dims[0] - 1, 0, grid.dims[1] - 1, 0, grid.dims[2] - 1);
    output->SetOrigin(grid.origin.data());
    output->SetSpacing(grid.spacing.data());
    output->SetDirectionMatrix(grid.direction(0, 0), grid.direction(0, 1), grid.direction(0, 2),
      grid.direction(1, 0), grid.direction(1, 1), grid.direction(1, 2), grid.direction(2, 0),
      grid.direction(2, 1), grid.direction(2, 2));
    vtkNew<vtkIntArray> labels;
    labels->SetName(repose::arrays::kLabels);
    labels->SetNumberOfTuples(static_cast<vtkIdType>(ph.labels.data.size()));
    std::copy(ph.labels.data.begin(), ph.labels.data.end(), labels->GetPointer(0));
    output->GetPointData()->SetScalars(labels);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  return 1;
}

void vtkReposePhantomSource::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Size: " << this->GetSizeName() << " (" << this->Size << ")\n";
  os << indent << "RestPose: " << this->GetRestPoseName() << "\n";
}
