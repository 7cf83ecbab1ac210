#ifndef vtkReposeBoneWeights_h
#define vtkReposeBoneWeights_h
// Harmonic bone weights of a tet mesh (one sparse factorization, every bone a right-hand side).
// Input: vtkUnstructuredGrid of tetrahedra with integer point data "FixedBone" (bone index of the
// node, -1 for free nodes). Output: a shallow copy of the input plus point data "Weights" (float,
// MaxInfluences components, largest first, each row sums to 1) and "BoneIds" (unsigned short,
// MaxInfluences components). The number of bones is NumberOfBones if > 0, else the number of
// joints in SkeletonJSON if set, else the largest FixedBone + 1.

#include "ReposeFiltersModule.h"
#include "vtkUnstructuredGridAlgorithm.h"

#include <string>

class REPOSEFILTERS_EXPORT vtkReposeBoneWeights : public vtkUnstructuredGridAlgorithm
{
public:
  static vtkReposeBoneWeights* New();
  vtkTypeMacro(vtkReposeBoneWeights, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum SolverType
  {
    CHOLMOD = 0,       ///< SuiteSparse CHOLMOD supernodal Cholesky (default, fastest)
    SIMPLICIAL_LDLT = 1  ///< Eigen's SimplicialLDLT
  };

  /// CHOLMOD's fill-reducing ordering (repose::FillOrdering): AUTOMATIC (default) picks AMD or METIS
  /// by the mesh's size, as measured fastest end to end (scripts/benchmark.py --orderings).
  enum OrderingType
  {
    AUTOMATIC = 0,
    AMD = 1,
    METIS = 2,
    CHOLMOD_DEFAULT = 3  ///< CHOLMOD's own strategy: AMD, then METIS as well if AMD's fill is high
  };

  vtkSetClampMacro(MaxInfluences, int, 1, 64);
  vtkGetMacro(MaxInfluences, int);
  vtkSetClampMacro(NumberOfBones, int, 0, 65535);
  vtkGetMacro(NumberOfBones, int);
  /// skeleton.json text; only its joint count is used (when NumberOfBones is 0).
  vtkSetStringMacro(SkeletonJSON);
  vtkGetStringMacro(SkeletonJSON);
  vtkSetClampMacro(Solver, int, CHOLMOD, SIMPLICIAL_LDLT);
  vtkGetMacro(Solver, int);
  void SetSolverToCHOLMOD() { this->SetSolver(CHOLMOD); }
  void SetSolverToSimplicialLDLT() { this->SetSolver(SIMPLICIAL_LDLT); }
  vtkSetClampMacro(Ordering, int, AUTOMATIC, CHOLMOD_DEFAULT);
  vtkGetMacro(Ordering, int);

  ///@{
  /// Report of the last successful run.
  vtkGetMacro(MinimumRawWeight, double);   ///< < 0 if the mesh violates the maximum principle
  vtkGetMacro(MaximumRawWeight, double);
  vtkGetMacro(MaximumSumError, double);    ///< max over nodes of |sum of raw weights - 1|
  vtkGetMacro(AssemblyTime, double);       ///< seconds: stiffness matrix and right-hand sides
  vtkGetMacro(AnalysisTime, double);       ///< seconds: ordering and symbolic analysis
  vtkGetMacro(FactorizationTime, double);  ///< seconds, the analysis included
  vtkGetMacro(SolveTime, double);          ///< seconds, all bones
  vtkGetMacro(SelectionTime, double);      ///< seconds, k largest weights per node
  vtkGetMacro(NumberOfFreeNodes, int);
  vtkGetMacro(NumberOfFixedNodes, int);
  const char* GetSolverName() { return this->SolverName.c_str(); }
  const char* GetOrderingName() { return this->OrderingName.c_str(); }  ///< the ordering used, e.g. "AMD"
  vtkGetMacro(FactorizationFlops, double);     ///< CHOLMOD's count for that ordering
  vtkGetMacro(FactorNonzeros, double);         ///< nonzeros of the Cholesky factor
  ///@}

  /// One-line description of the last failure, empty after success.
  const char* GetLastError() { return this->LastError.c_str(); }

protected:
  vtkReposeBoneWeights();
  ~vtkReposeBoneWeights() override;

  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int FillInputPortInformation(int port, vtkInformation* info) override;

  int MaxInfluences = 4;
  int NumberOfBones = 0;
  char* SkeletonJSON = nullptr;
  int Solver = CHOLMOD;
  int Ordering = AUTOMATIC;

  double MinimumRawWeight = 0;
  double MaximumRawWeight = 0;
  double MaximumSumError = 0;
  double AssemblyTime = 0;
  double AnalysisTime = 0;
  double FactorizationFlops = 0;
  double FactorNonzeros = 0;
  double FactorizationTime = 0;
  double SolveTime = 0;
  double SelectionTime = 0;
  int NumberOfFreeNodes = 0;
  int NumberOfFixedNodes = 0;
  std::string SolverName;
  std::string OrderingName;
  std::string LastError;

private:
  vtkReposeBoneWeights(const vtkReposeBoneWeights&) = delete;
  void operator=(const vtkReposeBoneWeights&) = delete;
};

#endif
