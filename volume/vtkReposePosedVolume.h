#ifndef vtkReposePosedVolume_h
#define vtkReposePosedVolume_h
// Posed volume by pull-resampling: every output voxel centre is located in a posed tet, mapped back
// to rest space with that tet's barycentric coordinates, and the rest image is sampled there.
// Input 0: rest vtkImageData (labels or intensities). Input 1: REST tet mesh (vtkUnstructuredGrid of
// tetrahedra). Input 2: POSED tet mesh (same topology). Output: vtkImageData on the rest lattice
// extended to hold the posed body (+PaddingVoxels), same spacing and direction matrix.
// Nearest: int labels (VTK_INT output); Linear: trilinear intensities (VTK_FLOAT output).
// The tet mesh stops short of the body's outer voxel layer (the mask is peeled before meshing), so the
// posed mesh is extrapolated outward on the voxel grid by ExtrapolationDistance; the mesh boundary, the rest tets,
// nodes and scalars are converted once and cached between poses. RestrictToSubExtent resamples only a
// block of the output (e.g. the slices a viewer shows).

#include "ReposeVolumeModule.h"
#include "vtkImageAlgorithm.h"

class REPOSEVOLUME_EXPORT vtkReposePosedVolume : public vtkImageAlgorithm
{
public:
  static vtkReposePosedVolume* New();
  vtkTypeMacro(vtkReposePosedVolume, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum
  {
    Nearest = 0,
    Linear = 1
  };
  vtkSetClampMacro(Interpolation, int, Nearest, Linear);
  vtkGetMacro(Interpolation, int);
  void SetInterpolationToNearest() { this->SetInterpolation(Nearest); }
  void SetInterpolationToLinear() { this->SetInterpolation(Linear); }

  /// Output the map itself instead of a resampled image: a 3-component float array "Displacement",
  /// for every output voxel the displacement (mm, physical LPS axes) from its centre to the rest point
  /// Linear interpolation samples the rest image at (0 where the map does not reach). A known-answer
  /// field for deformable registration: warping the rest CT by it gives the posed CT. Default off.
  vtkSetMacro(OutputDisplacement, bool);
  vtkGetMacro(OutputDisplacement, bool);
  vtkBooleanMacro(OutputDisplacement, bool);

  /// Value of voxels outside the posed mesh (and of rest points outside the rest image).
  vtkSetMacro(BackgroundValue, double);
  vtkGetMacro(BackgroundValue, double);

  /// Extra voxels on every side of the posed body's bounding box.
  vtkSetClampMacro(PaddingVoxels, int, 0, 1000);
  vtkGetMacro(PaddingVoxels, int);

  /// The output lattice is the rest image's, holding the posed body and, while that at most doubles
  /// the rest image's voxels, the rest extent too (a pose in place keeps the rest voxel indices); a
  /// body that moved away (root motion) gets a grid of its own size, its margin covering the
  /// extrapolation.
  /// A grid of more than MaxVoxels voxels is an error that gives its size and the body's span
  /// (default 512 M = 5.12e8, 2 GB of labels; 0 = no limit).
  vtkSetClampMacro(MaxVoxels, double, 0, 1e15);
  vtkGetMacro(MaxVoxels, double);

  /// How far (mm) the posed mesh is extrapolated outward to fill voxels outside it: ceil(distance /
  /// finest spacing) + 2 layers of voxel neighbours, each voxel taking the map of the neighbouring tet
  /// it lies least far outside of; labels only where the sampled rest label is not BackgroundValue,
  /// intensities only inside the rest image. Negative = automatic (2 x the rest image's largest
  /// spacing, the default); 0 = off.
  vtkSetMacro(ExtrapolationDistance, double);
  vtkGetMacro(ExtrapolationDistance, double);

  /// Labels only: after the pull, place every bone's voxels exactly where its rigid motion takes them
  /// (bones and their labels from the rest mesh's point data "FixedBone"). Default on.
  vtkSetMacro(RigidBones, bool);
  vtkGetMacro(RigidBones, bool);
  vtkBooleanMacro(RigidBones, bool);
  /// Voxels changed by the rigid-bone pass in the last execution.
  vtkGetMacro(RigidBoneVoxels, vtkIdType);
  /// Voxels that two bones' rigid motions both claimed in the last execution (bones colliding).
  vtkGetMacro(ContestedBoneVoxels, vtkIdType);

  /// Sub-extent output (e.g. only the slices a viewer shows): with RestrictToSubExtent on, only the voxels
  /// of OutputSubExtent {i0, i1, j0, j1, k0, k1} (indices of the full posed grid, clamped to it) are
  /// resampled. The output then has that extent (also as its whole extent), with the full grid's
  /// origin, spacing and direction, and its voxels equal the same voxels of the full output. Error if
  /// the clamped extent is empty. Default off. FullOutputExtent is the full posed grid's extent (known
  /// after UpdateInformation), to choose sub-extents from.
  vtkSetMacro(RestrictToSubExtent, bool);
  vtkGetMacro(RestrictToSubExtent, bool);
  vtkBooleanMacro(RestrictToSubExtent, bool);
  vtkSetVector6Macro(OutputSubExtent, int);
  vtkGetVector6Macro(OutputSubExtent, int);
  vtkGetVector6Macro(FullOutputExtent, int);

  /// Statistics of the last execution.
  vtkGetMacro(CoveredVoxels, vtkIdType);
  /// Voxels outside every posed tet filled by the extrapolation.
  vtkGetMacro(ExtrapolatedVoxels, vtkIdType);
  vtkGetMacro(InvertedTets, vtkIdType);
  /// Seconds spent in the resampler itself.
  vtkGetMacro(LastResampleTime, double);

  void SetRestMeshConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }
  void SetPosedMeshConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(2, output); }
  void SetRestMeshData(vtkDataObject* mesh) { this->SetInputData(1, mesh); }
  void SetPosedMeshData(vtkDataObject* mesh) { this->SetInputData(2, mesh); }

protected:
  vtkReposePosedVolume();
  ~vtkReposePosedVolume() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  int Interpolation = Nearest;
  double BackgroundValue = 0;
  int PaddingVoxels = 2;
  double MaxVoxels = 512e6;
  double ExtrapolationDistance = -1.0;
  bool RigidBones = true;
  bool OutputDisplacement = false;
  vtkIdType RigidBoneVoxels = 0;
  vtkIdType ContestedBoneVoxels = 0;
  vtkIdType CoveredVoxels = 0;
  vtkIdType ExtrapolatedVoxels = 0;
  vtkIdType InvertedTets = 0;
  double LastResampleTime = 0;
  bool RestrictToSubExtent = false;
  int OutputSubExtent[6] = { 0, -1, 0, -1, 0, -1 };
  int FullOutputExtent[6] = { 0, -1, 0, -1, 0, -1 };

private:
  struct Internals;  // conversions and mesh boundary cached between poses
  Internals* Internal;

  vtkReposePosedVolume(const vtkReposePosedVolume&) = delete;
  void operator=(const vtkReposePosedVolume&) = delete;
};

#endif
