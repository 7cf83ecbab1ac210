#ifndef vtkReposeCorotationalRelax_h
#define vtkReposeCorotationalRelax_h
// Refines a skinned tet mesh by a static corotational linear-elastic solve (Mueller & Gross 2004):
// bone nodes stay at their skinned (rigid) positions, the soft tissue settles so that it keeps its
// volume. Input 0: the posed (skinned) mesh, the warm start; input 1: the rest mesh with point data
// "FixedBone" (the stress-free shape and the Dirichlet nodes). Output: input 0 with relaxed points.

#include "ReposeFiltersModule.h"
#include "vtkUnstructuredGridAlgorithm.h"

class REPOSEFILTERS_EXPORT vtkReposeCorotationalRelax : public vtkUnstructuredGridAlgorithm
{
public:
  static vtkReposeCorotationalRelax* New();
  vtkTypeMacro(vtkReposeCorotationalRelax, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// Poisson's ratio in (-1, 0.5); default 0.49 (nearly incompressible tissue).
  vtkSetClampMacro(PoissonRatio, double, -0.99, 0.4999);
  vtkGetMacro(PoissonRatio, double);
  /// Corotational outer iterations (rotations re-extracted, solved again); default 1.
  vtkSetClampMacro(OuterIterations, int, 1, 100);
  vtkGetMacro(OuterIterations, int);
  /// CG relative residual; default 1e-6.
  vtkSetClampMacro(Tolerance, double, 1e-14, 1.0);
  vtkGetMacro(Tolerance, double);
  vtkSetClampMacro(MaxIterations, int, 1, 1000000);
  vtkGetMacro(MaxIterations, int);
  /// 0 = Jacobi (threaded, default), 1 = incomplete Cholesky.
  vtkSetClampMacro(Preconditioner, int, 0, 1);
  vtkGetMacro(Preconditioner, int);

  void SetRestMeshConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }
  void SetRestMeshData(vtkDataObject* mesh) { this->SetInputData(1, mesh); }

  /// Figures of the last execution.
  vtkGetMacro(CGIterations, int);          ///< summed over outer iterations
  vtkGetMacro(RelativeResidual, double);   ///< of the last outer iteration
  vtkGetMacro(InvertedBefore, int);
  vtkGetMacro(InvertedAfter, int);
  vtkGetMacro(LastRelaxTime, double);

protected:
  vtkReposeCorotationalRelax();
  ~vtkReposeCorotationalRelax() override = default;
  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  double PoissonRatio = 0.49;
  int OuterIterations = 1;
  double Tolerance = 1e-6;
  int MaxIterations = 2000;
  int Preconditioner = 0;
  int CGIterations = 0;
  double RelativeResidual = 0;
  int InvertedBefore = 0;
  int InvertedAfter = 0;
  double LastRelaxTime = 0;

private:
  vtkReposeCorotationalRelax(const vtkReposeCorotationalRelax&) = delete;
  void operator=(const vtkReposeCorotationalRelax&) = delete;
};

#endif
