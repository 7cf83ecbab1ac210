#ifndef ReposeMaskContouring_h
#define ReposeMaskContouring_h
// The steps of contouring a mask image into a surface (vtkReposeSurfaceExtractor::ContourMask):
// to the index frame, optional antialiased resampling, padding and contouring, smoothing and
// decimation, and back to physical coordinates.

#include "vtkSmartPointer.h"

class vtkImageData;
class vtkPolyData;

namespace repose_vtk
{
/// The same voxels in the axis-aligned index frame: point = spacing * ijk.
vtkSmartPointer<vtkImageData> InIndexFrame(vtkImageData* mask);

/// local resampled as float by an antialiased (sinc) resize to meshingSpacing (not finer than its
/// own spacing), or null when meshingSpacing is 0 or not coarser than 1.01 times its finest spacing.
vtkSmartPointer<vtkImageData> ResampledMask(vtkImageData* local, double meshingSpacing);

/// The surface of a mask padded by a background layer all around (so the surface closes where the
/// mask touches the image border): a resampled mask contoured at 0.5, another by the discrete
/// contour of its non-zero voxels.
vtkSmartPointer<vtkPolyData> ContourPadded(vtkImageData* volume, bool resampled);

/// Windowed-sinc smoothing (iterations > 0) then quadric decimation (targetReduction > 0).
vtkSmartPointer<vtkPolyData> SmoothedAndDecimated(
  vtkPolyData* surface, int iterations, double passBand, double targetReduction);

/// Index frame -> physical: x = origin + direction * local, in double precision.
vtkSmartPointer<vtkPolyData> ToPhysical(vtkPolyData* surface, vtkImageData* mask);
}

#endif
