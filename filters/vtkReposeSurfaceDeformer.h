#ifndef vtkReposeSurfaceDeformer_h
#define vtkReposeSurfaceDeformer_h
// Moves bound surfaces with the posed tet mesh: input 0 = surface with "BoundTet"/"BoundWeights"
// (from vtkReposeSurfaceBinding), input 1 = posed tet mesh (same topology as the rest mesh used for
// binding). Output: the surface with moved points; normals are dropped (stale after deformation).
// The binding is cached and rebuilt only when input 0 changes, so a new pose costs one pass. Output
// points are float and the vtkPoints object is reused (marked Modified) while the vertex count is
// unchanged: a consumer holding an earlier output's points sees them change (deep-copy to keep).

#include "ReposeFiltersModule.h"
#include "vtkPolyDataAlgorithm.h"

class REPOSEFILTERS_EXPORT vtkReposeSurfaceDeformer : public vtkPolyDataAlgorithm
{
public:
  static vtkReposeSurfaceDeformer* New();
  vtkTypeMacro(vtkReposeSurfaceDeformer, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void SetPosedMeshConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }
  void SetPosedMeshData(vtkDataObject* mesh) { this->SetInputData(1, mesh); }

  /// Seconds spent moving the points in the last execution.
  vtkGetMacro(LastDeformTime, double);

protected:
  vtkReposeSurfaceDeformer();
  ~vtkReposeSurfaceDeformer() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  double LastDeformTime = 0;

private:
  vtkReposeSurfaceDeformer(const vtkReposeSurfaceDeformer&) = delete;
  void operator=(const vtkReposeSurfaceDeformer&) = delete;

  struct Internals;
  Internals* Impl;
};

#endif
