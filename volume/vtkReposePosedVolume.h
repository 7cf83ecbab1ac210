#ifndef vtkReposePosedVolume_h
#define vtkReposePosedVolume_h
// Posed volume by pull-resampling: every output voxel centre is located in a posed tet, mapped back
// to rest space with that tet's barycentric coordinates, and the rest image is sampled there.
// Input 0: rest vtkImageData (labels or intensities). Input 1: REST tet mesh (vtkUnstructuredGrid of
// tetrahedra). Input 2: POSED tet mesh (same topology). Output: vtkImageData on the rest lattice
// extended to hold the posed body (+PaddingVoxels), same spacing and direction matrix.
// Nearest: int labels (VTK_INT output); Linear: trilinear intensities (VTK_FLOAT output).

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

  /// Value of voxels outside the posed mesh (and of rest points outside the rest image).
  vtkSetMacro(BackgroundValue, double);
  vtkGetMacro(BackgroundValue, double);

  /// Extra voxels on every side of the posed body's bounding box.
  vtkSetClampMacro(PaddingVoxels, int, 0, 1000);
  vtkGetMacro(PaddingVoxels, int);

  /// Statistics of the last execution.
  vtkGetMacro(CoveredVoxels, vtkIdType);
  vtkGetMacro(InvertedTets, vtkIdType);
  /// Seconds spent in the resampler itself.
  vtkGetMacro(LastResampleTime, double);

  void SetRestMeshConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }
  void SetPosedMeshConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(2, output); }
  void SetRestMeshData(vtkDataObject* mesh) { this->SetInputData(1, mesh); }
  void SetPosedMeshData(vtkDataObject* mesh) { this->SetInputData(2, mesh); }

protected:
  vtkReposePosedVolume();
  ~vtkReposePosedVolume() override = default;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  int Interpolation = Nearest;
  double BackgroundValue = 0;
  int PaddingVoxels = 2;
  vtkIdType CoveredVoxels = 0;
  vtkIdType InvertedTets = 0;
  double LastResampleTime = 0;

private:
  vtkReposePosedVolume(const vtkReposePosedVolume&) = delete;
  void operator=(const vtkReposePosedVolume&) = delete;
};

#endif
