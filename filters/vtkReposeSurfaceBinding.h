#ifndef vtkReposeSurfaceBinding_h
#define vtkReposeSurfaceBinding_h
// Binds surface vertices to the rest tet mesh: input 0 = rest surfaces (vtkPolyData), input 1 = rest
// tet mesh (vtkUnstructuredGrid of tetrahedra). Output: the surface with point data "BoundTet" (int)
// and "BoundWeights" (float, 4 components: barycentric coordinates; negative outside the mesh).
// The tet locator is kept while the tet mesh's points and cells are unchanged, so binding several
// surfaces (organs, vessels, a catheter) to one case builds it once.

#include "ReposeFiltersModule.h"
#include "vtkPolyDataAlgorithm.h"

class REPOSEFILTERS_EXPORT vtkReposeSurfaceBinding : public vtkPolyDataAlgorithm
{
public:
  static vtkReposeSurfaceBinding* New();
  vtkTypeMacro(vtkReposeSurfaceBinding, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void SetTetMeshConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }
  void SetTetMeshData(vtkDataObject* mesh) { this->SetInputData(1, mesh); }

  /// Vertices outside every tet in the last execution (bound to the nearest tet, extrapolated).
  vtkGetMacro(OutsideCount, vtkIdType);

protected:
  vtkReposeSurfaceBinding();
  ~vtkReposeSurfaceBinding() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  vtkIdType OutsideCount = 0;

private:
  vtkReposeSurfaceBinding(const vtkReposeSurfaceBinding&) = delete;
  void operator=(const vtkReposeSurfaceBinding&) = delete;
  struct Internals;
  Internals* Impl;
};

#endif
