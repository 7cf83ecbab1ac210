#include "vtkReposeBoneWeights.h"

#include "vtkCellArray.h"
#include "vtkCellArrayIterator.h"
#include "vtkCellType.h"
#include "vtkDataArray.h"
#include "vtkFloatArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkSmartPointer.h"
#include "vtkUnsignedShortArray.h"
#include "vtkUnstructuredGrid.h"

#include "ReposeMeshConversion.h"
#include "harmonic_weights.h"
#include "skeleton.h"
#include "array_names.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

vtkStandardNewMacro(vtkReposeBoneWeights);

namespace
{
// vtkUnstructuredGrid of tets + "FixedBone" -> repose::TetMesh (no tetLabel needed here).
repose::TetMesh ToTetMesh(vtkUnstructuredGrid* grid)
{
  repose::TetMesh mesh;
  const vtkIdType np = grid->GetNumberOfPoints(), nc = grid->GetNumberOfCells();
  mesh.nodes = repose_vtk::ToPoints(grid->GetPoints());
  mesh.tets.resize(nc, 4);
  auto it = vtk::TakeSmartPointer(grid->GetCells()->NewIterator());
  vtkIdType c = 0;
  for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell(), ++c)
  {
    vtkIdType n;
    const vtkIdType* ids;
    it->GetCurrentCell(n, ids);
    if (grid->GetCellType(c) != VTK_TETRA || n != 4)
      throw std::invalid_argument("cell " + std::to_string(c) +
        " is not a tetrahedron; the weights need a pure tet mesh");
    for (int k = 0; k < 4; ++k)
      mesh.tets(c, k) = static_cast<int>(ids[k]);
  }
  vtkDataArray* fixed = grid->GetPointData()->GetArray(repose::arrays::kFixedBone);
  if (!fixed || fixed->GetNumberOfComponents() != 1 || fixed->GetNumberOfTuples() != np)
    throw std::invalid_argument(
      "input has no 1-component point data \"FixedBone\" with a value per node (bone index, -1 for free nodes)");
  mesh.fixedBone.resize(np);
  for (vtkIdType i = 0; i < np; ++i)
  {
    const double b = fixed->GetComponent(i, 0);
    if (b != std::floor(b))
      throw std::invalid_argument("FixedBone of node " + std::to_string(i) + " is not an integer");
    mesh.fixedBone[i] = static_cast<int>(b);
  }
  return mesh;
}
}

vtkReposeBoneWeights::vtkReposeBoneWeights() = default;

vtkReposeBoneWeights::~vtkReposeBoneWeights()
{
  this->SetSkeletonJSON(nullptr);
}

int vtkReposeBoneWeights::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkUnstructuredGrid");
  return 1;
}

int vtkReposeBoneWeights::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0], 0);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector, 0);
  this->LastError.clear();
  if (!input || !output)
  {
    this->LastError = "missing input or output";
    vtkErrorMacro(<< this->LastError);
    return 0;
  }
  try
  {
    const repose::TetMesh mesh = ToTetMesh(input);
    repose::HarmonicWeightsOptions options;
    options.maxInfluences = this->MaxInfluences;
    options.boneCount = this->NumberOfBones;
    if (options.boneCount <= 0 && this->SkeletonJSON && *this->SkeletonJSON)
      options.boneCount = static_cast<int>(repose::parseSkeletonJson(this->SkeletonJSON).size());
    options.solver = this->Solver == SIMPLICIAL_LDLT ? repose::HarmonicSolver::EigenSimplicialLDLT
                                                     : repose::HarmonicSolver::CholmodSupernodal;
    static_assert(int(repose::FillOrdering::CholmodDefault) == CHOLMOD_DEFAULT, "same order of values");
    options.ordering = static_cast<repose::FillOrdering>(this->Ordering);
    repose::HarmonicWeightsReport report;
    const repose::SparseWeights weights = repose::harmonicWeights(mesh, options, &report);

    const int k = weights.k;
    const vtkIdType np = input->GetNumberOfPoints();
    vtkNew<vtkFloatArray> w;
    w->SetName(repose::arrays::kWeights);
    w->SetNumberOfComponents(k);
    w->SetNumberOfTuples(np);
    std::copy(weights.weight.begin(), weights.weight.end(), w->GetPointer(0));
    vtkNew<vtkUnsignedShortArray> b;
    b->SetName(repose::arrays::kBoneIds);
    b->SetNumberOfComponents(k);
    b->SetNumberOfTuples(np);
    std::copy(weights.bone.begin(), weights.bone.end(), b->GetPointer(0));

    output->ShallowCopy(input);
    output->GetPointData()->AddArray(w);
    output->GetPointData()->AddArray(b);

    this->MinimumRawWeight = report.minRawWeight;
    this->MaximumRawWeight = report.maxRawWeight;
    this->MaximumSumError = report.maxSumError;
    this->AssemblyTime = report.assembleSeconds;
    this->AnalysisTime = report.analyzeSeconds;
    this->FactorizationFlops = report.factorFlops;
    this->FactorNonzeros = report.factorNonzeros;
    this->FactorizationTime = report.factorSeconds;
    this->SolveTime = report.solveSeconds;
    this->SelectionTime = report.selectSeconds;
    this->NumberOfFreeNodes = report.freeNodes;
    this->NumberOfFixedNodes = report.fixedNodes;
    this->SolverName = report.solver;
    this->OrderingName = report.ordering;
  }
  catch (const std::exception& e)
  {
    this->LastError = e.what();
    vtkErrorMacro(<< "bone weights: " << e.what());
    return 0;
  }
  return 1;
}

void vtkReposeBoneWeights::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "MaxInfluences: " << this->MaxInfluences << "\n";
  os << indent << "NumberOfBones: " << this->NumberOfBones << "\n";
  os << indent << "SkeletonJSON: " << (this->SkeletonJSON ? "(set)" : "(none)") << "\n";
  os << indent << "Solver: " << (this->Solver == CHOLMOD ? "CHOLMOD" : "SimplicialLDLT") << "\n";
  os << indent << "Ordering: " << this->Ordering << "\n";
  os << indent << "MinimumRawWeight: " << this->MinimumRawWeight << "\n";
  os << indent << "MaximumSumError: " << this->MaximumSumError << "\n";
  os << indent << "FactorizationTime: " << this->FactorizationTime << "\n";
  os << indent << "SolveTime: " << this->SolveTime << "\n";
}
