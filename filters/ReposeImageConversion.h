#ifndef ReposeImageConversion_h
#define ReposeImageConversion_h
// vtkImageData <-> core volumes on the same physical lattice (origin, spacing, direction), shared by
// the filters. Header-only and not wrapped: it exchanges core (Eigen) types.

#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkMatrix3x3.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkSMPTools.h"
#include "vtkSmartPointer.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkUnsignedCharArray.h"

#include <algorithm>

#include "image_grid.h"

namespace repose_vtk
{

/// The image's lattice as a core grid (the first voxel of the extent is the core's index 0).
inline repose::ImageGrid ToGrid(vtkImageData* image)
{
  repose::ImageGrid g;
  int ext[6];
  image->GetExtent(ext);
  g.dims = { ext[1] - ext[0] + 1, ext[3] - ext[2] + 1, ext[5] - ext[4] + 1 };
  double origin[3];
  image->TransformIndexToPhysicalPoint(ext[0], ext[2], ext[4], origin);
  const double* spacing = image->GetSpacing();
  vtkMatrix3x3* d = image->GetDirectionMatrix();
  for (int r = 0; r < 3; ++r)
  {
    g.origin[r] = origin[r];
    g.spacing[r] = spacing[r];
    for (int c = 0; c < 3; ++c)
    {
      g.direction(r, c) = d->GetElement(r, c);
    }
  }
  return g;
}

/// vtkImageData (any scalar type, one component) -> core volume. False when the image has no
/// single-component scalars or their count does not match the extent.
template <class T>
bool ToVolume(vtkImageData* image, repose::Volume<T>& volume)
{
  vtkDataArray* scalars = image ? image->GetPointData()->GetScalars() : nullptr;
  if (!scalars || scalars->GetNumberOfComponents() != 1)
  {
    return false;
  }
  volume.grid = ToGrid(image);
  const vtkIdType n = scalars->GetNumberOfTuples();
  if (n != static_cast<vtkIdType>(volume.grid.voxelCount()))
  {
    return false;
  }
  volume.data.resize(static_cast<std::size_t>(n));
  T* out = volume.data.data();
  vtkSMPTools::For(0, n, [&](vtkIdType b, vtkIdType e) {
    for (vtkIdType p = b; p < e; ++p)
    {
      out[p] = static_cast<T>(scalars->GetComponent(p, 0));
    }
  });
  return true;
}

/// The direction matrix of a core grid, row-major as VTK takes it.
inline void DirectionArray(const repose::ImageGrid& g, double d[9])
{
  for (int r = 0; r < 3; ++r)
  {
    for (int c = 0; c < 3; ++c)
    {
      d[3 * r + c] = g.direction(r, c);
    }
  }
}

/// Core volume -> vtkImageData with the volume's lattice and one named scalar array of ArrayT
/// (vtkUnsignedCharArray for masks, vtkIntArray for labels).
template <class ArrayT, class T>
vtkSmartPointer<vtkImageData> ToImage(const repose::Volume<T>& volume, const char* name)
{
  auto image = vtkSmartPointer<vtkImageData>::New();
  const auto& g = volume.grid;
  image->SetExtent(0, g.dims[0] - 1, 0, g.dims[1] - 1, 0, g.dims[2] - 1);
  image->SetOrigin(g.origin.data());
  image->SetSpacing(g.spacing.data());
  double d[9];
  DirectionArray(g, d);
  image->SetDirectionMatrix(d);
  vtkNew<ArrayT> values;
  values->SetName(name);
  values->SetNumberOfTuples(static_cast<vtkIdType>(volume.data.size()));
  std::copy(volume.data.begin(), volume.data.end(), values->GetPointer(0));
  image->GetPointData()->SetScalars(values);
  return image;
}

/// Core mask -> unsigned char vtkImageData named "Mask" with the mask's lattice.
inline vtkSmartPointer<vtkImageData> ToImage(const repose::MaskVolume& mask)
{
  return ToImage<vtkUnsignedCharArray>(mask, "Mask");
}

/// Announces a source's output lattice (extent, origin, spacing, direction, scalar type) in
/// RequestInformation.
inline void SetOutputGeometry(const repose::ImageGrid& g, vtkInformation* outInfo, int scalarType)
{
  const int extent[6] = { 0, g.dims[0] - 1, 0, g.dims[1] - 1, 0, g.dims[2] - 1 };
  double direction[9];
  DirectionArray(g, direction);
  outInfo->Set(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), extent, 6);
  outInfo->Set(vtkDataObject::ORIGIN(), g.origin.data(), 3);
  outInfo->Set(vtkDataObject::SPACING(), g.spacing.data(), 3);
  outInfo->Set(vtkDataObject::DIRECTION(), direction, 9);
  vtkDataObject::SetPointDataActiveScalarInfo(outInfo, scalarType, 1);
}

} // namespace repose_vtk

#endif
