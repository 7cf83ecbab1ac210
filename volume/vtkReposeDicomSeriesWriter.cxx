#include "vtkReposeDicomSeriesWriter.h"

#include "vtkDataArray.h"
#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMatrix3x3.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkStringArray.h"

#include "ReposeDicomSeries.h"

#include "gdcmUIDGenerator.h"

#include <stdexcept>

vtkStandardNewMacro(vtkReposeDicomSeriesWriter);

namespace
{

// The input as ITK's float volume, same geometry (LPS), voxel values unchanged.
itk::Image<float, 3>::Pointer ToItk(vtkImageData* input)
{
  auto image = itk::Image<float, 3>::New();
  int dims[3];
  input->GetDimensions(dims);
  itk::Image<float, 3>::RegionType region;
  region.SetSize({ { static_cast<itk::SizeValueType>(dims[0]), static_cast<itk::SizeValueType>(dims[1]),
    static_cast<itk::SizeValueType>(dims[2]) } });
  image->SetRegions(region);
  image->Allocate();
  // The first voxel's place: VTK's origin is that of index 0, the extent may start elsewhere.
  int extent[6];
  input->GetExtent(extent);
  double first[3];
  input->TransformIndexToPhysicalPoint(extent[0], extent[2], extent[4], first);
  image->SetOrigin(first);
  image->SetSpacing(input->GetSpacing());
  itk::Image<float, 3>::DirectionType direction;
  for (int r = 0; r < 3; ++r)
  {
    for (int c = 0; c < 3; ++c)
    {
      direction(r, c) = input->GetDirectionMatrix()->GetElement(r, c);
    }
  }
  image->SetDirection(direction);
  vtkDataArray* scalars = input->GetPointData()->GetScalars();
  float* to = image->GetBufferPointer();
  for (vtkIdType i = 0, n = scalars->GetNumberOfTuples(); i < n; ++i)
  {
    to[i] = static_cast<float>(scalars->GetTuple1(i));
  }
  return image;
}

}

vtkReposeDicomSeriesWriter::vtkReposeDicomSeriesWriter() = default;

void vtkReposeDicomSeriesWriter::AssignNewStudy(vtkImageData* image)
{
  if (!image || image->GetFieldData()->GetAbstractArray("DicomTags"))
  {
    return;
  }
  gdcm::UIDGenerator uids;
  auto tags = vtkSmartPointer<vtkStringArray>::New();
  tags->SetName("DicomTags");
  tags->InsertNextValue("0010|0010=ANONYMOUS");
  tags->InsertNextValue("0010|0020=ANONYMOUS");
  tags->InsertNextValue(std::string("0020|000d=") + uids.Generate());
  tags->InsertNextValue(std::string("0020|0052=") + uids.Generate());
  image->GetFieldData()->AddArray(tags);
}

vtkReposeDicomSeriesWriter::~vtkReposeDicomSeriesWriter()
{
  this->SetSeriesDescription(nullptr);
}

int vtkReposeDicomSeriesWriter::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector*)
{
  vtkImageData* input = vtkImageData::GetData(inputVector[0]);
  auto fail = [this](const std::string& reason) { return this->Fail(reason); };
  if (!input || !input->GetPointData()->GetScalars() || input->GetNumberOfPoints() < 1 ||
    input->GetPointData()->GetScalars()->GetNumberOfComponents() != 1)
  {
    return fail("input has no one-component image scalars");
  }
  const auto image = ToItk(input);
  const repose::DicomTags carried = repose::DicomTagsOf(input);
  const std::string description = this->SeriesDescription ? this->SeriesDescription : "";
  return this->WriteAtomically(
    [&](const std::string& folder) { repose::WriteDicomSeries(image, folder, carried, description); });
}

void vtkReposeDicomSeriesWriter::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "SeriesDescription: " << (this->SeriesDescription ? this->SeriesDescription : "(none)") << "\n";
}
