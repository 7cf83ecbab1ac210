#pragma once
// Images for display in patient coordinates. VTK 9.1's image mappers ignore the direction matrix,
// so a slice view that showed the voxel grid as it is would mirror any scan whose direction is not
// the identity (NIfTI from a scanner is often diag(-1,-1,1): patient left and posterior flipped).
// The copy made here has the identity direction and an extent starting at 0, and its world
// coordinates are the input's physical (LPS) millimetres: x towards the patient's left, y posterior,
// z superior.
#include <vtkSmartPointer.h>

class vtkImageData;

namespace repose {

/// An axis-aligned direction (a signed permutation, as scanners write) is undone exactly by
/// reordering voxels; an oblique one is resampled onto an axis-aligned grid covering the image
/// (nearest voxel with `nearest`, trilinear otherwise; outside = `background`). Null in, null out.
vtkSmartPointer<vtkImageData> lpsAlignedImage(vtkImageData* image, bool nearest, double background = 0);

}  // namespace repose
