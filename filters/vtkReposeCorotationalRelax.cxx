#include "vtkReposeCorotationalRelax.h"

#include <chrono>
#include <string>

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkDataArray.h"
#include "vtkIdList.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkUnstructuredGrid.h"

#include <exception>

#include "ReposeMeshConversion.h"
#include "ReposeWeightArrays.h"
#include "body_segments.h"
#include "corotational_fem.h"
#include "progress_line.h"
#include "skeleton.h"
#include "array_names.h"

vtkStandardNewMacro(vtkReposeCorotationalRelax);

// The filter's enums are the core's, value for value: RequestData passes them on by a cast.
namespace
{
constexpr bool SameValue(int filterValue, int coreValue)
{
  return filterValue == coreValue;
}
using Core = repose::CorotationalOptions;
using Relax = vtkReposeCorotationalRelax;
static_assert(SameValue(Relax::PRECONDITIONER_JACOBI, Core::Jacobi) &&
  SameValue(Relax::PRECONDITIONER_INCOMPLETE_CHOLESKY, Core::IncompleteCholesky) &&
  SameValue(Relax::PRECONDITIONER_CHOLMOD, Core::Cholmod) &&
  SameValue(Relax::PRECONDITIONER_BLOCK_JACOBI, Core::BlockJacobi) &&
  SameValue(Relax::PRECONDITIONER_TWO_LEVEL, Core::TwoLevel));
static_assert(SameValue(Relax::MODEL_LINEAR, Core::Linear) &&
  SameValue(Relax::MODEL_FIXED_COROTATED, Core::FixedCorotated));
static_assert(SameValue(Relax::CONTINUATION_NEVER, Core::Never) &&
  SameValue(Relax::CONTINUATION_IF_INVERTED, Core::IfInverted) &&
  SameValue(Relax::CONTINUATION_ALWAYS, Core::Always));
}

vtkReposeCorotationalRelax::vtkReposeCorotationalRelax()
{
  this->SetNumberOfInputPorts(2);
  // One source of defaults: the core's.
  const repose::CorotationalOptions defaults;
  this->PoissonRatio = defaults.poisson;
  this->OuterIterations = defaults.outerIterations;
  this->Tolerance = defaults.tolerance;
  this->MaxIterations = defaults.maxCgIterations;
  this->Preconditioner = defaults.preconditioner;
  this->Model = defaults.model;
  this->MaxNewtonIterations = defaults.maxNewtonIterations;
  this->StepTolerance = defaults.stepTolerance;
  this->EnergyTolerance = defaults.energyTolerance;
  this->RegionVolumeStiffness = defaults.regionVolumeStiffness;
  this->RegionVolumeTolerance = defaults.regionVolumeTolerance;
  this->InversionBarrier = defaults.inversionBarrier;
  this->UntangleRelaxRings = defaults.untangleRelaxRings;
  this->StrainedRegionThreshold = defaults.strainedRegionThreshold;
  this->StrainedRegionRings = defaults.strainedRegionRings;
  this->Continuation = defaults.continuation;
}

vtkReposeCorotationalRelax::~vtkReposeCorotationalRelax()
{
  this->SetSkeletonJSON(nullptr);
}

int vtkReposeCorotationalRelax::FillInputPortInformation(int port, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkUnstructuredGrid");
  (void)port;
  return 1;
}

int vtkReposeCorotationalRelax::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  this->Cancelled = false;
  vtkUnstructuredGrid* posed = vtkUnstructuredGrid::GetData(inputVector[0]);
  vtkUnstructuredGrid* rest = vtkUnstructuredGrid::GetData(inputVector[1]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  if (!posed || !rest || !posed->GetPoints() || !rest->GetPoints())
  {
    vtkErrorMacro("needs the posed tet mesh (input 0) and the rest tet mesh (input 1)");
    return 0;
  }
  vtkDataArray* fixed = rest->GetPointData()->GetArray(repose::arrays::kFixedBone);
  if (!fixed || rest->GetNumberOfPoints() != posed->GetNumberOfPoints() ||
    rest->GetNumberOfCells() != posed->GetNumberOfCells())
  {
    vtkErrorMacro("the rest mesh needs point data FixedBone and the same nodes and tets as the posed mesh");
    return 0;
  }
  try
  {
    const vtkIdType nt = rest->GetNumberOfCells();
    repose::Tets tets(nt, 4);
    vtkNew<vtkIdList> ids;
    for (vtkIdType c = 0; c < nt; ++c)
    {
      rest->GetCellPoints(c, ids);
      if (ids->GetNumberOfIds() != 4)
      {
        vtkErrorMacro("cell " << c << " of the rest mesh is not a tetrahedron");
        return 0;
      }
      for (int k = 0; k < 4; ++k)
      {
        tets(c, k) = static_cast<int>(ids->GetId(k));
      }
    }
    std::vector<int> fixedBone(static_cast<std::size_t>(fixed->GetNumberOfTuples()));
    for (vtkIdType v = 0; v < fixed->GetNumberOfTuples(); ++v)
    {
      fixedBone[static_cast<std::size_t>(v)] = static_cast<int>(fixed->GetTuple1(v));
    }
    const repose::Points restNodes = repose_vtk::ToPoints(rest->GetPoints());
    repose::Points nodes = repose_vtk::ToPoints(posed->GetPoints());

    repose::CorotationalOptions options;
    options.poisson = this->PoissonRatio;
    options.outerIterations = this->OuterIterations;
    options.tolerance = this->Tolerance;
    options.maxCgIterations = this->MaxIterations;
    options.preconditioner = static_cast<repose::CorotationalOptions::Preconditioner>(this->Preconditioner);
    options.model = static_cast<repose::CorotationalOptions::Model>(this->Model);
    options.maxNewtonIterations = this->MaxNewtonIterations;
    options.stepTolerance = this->StepTolerance;
    options.energyTolerance = this->EnergyTolerance;
    options.regionVolumeStiffness = this->RegionVolumeStiffness;
    options.regionVolumeTolerance = this->RegionVolumeTolerance;
    options.inversionBarrier = this->InversionBarrier;
    options.untangleRelaxRings = this->UntangleRelaxRings;
    options.strainedRegionThreshold = this->StrainedRegionThreshold;
    options.strainedRegionRings = this->StrainedRegionRings;
    options.continuation = static_cast<repose::CorotationalOptions::Continuation>(this->Continuation);
    if (this->SkeletonJSON && *this->SkeletonJSON)
    {
      for (const repose::Joint& joint : repose::parseSkeletonJson(this->SkeletonJSON).joints)
      {
        options.boneParents.push_back(joint.parent);
      }
    }
    // Segments need the rest mesh's weights; without them the whole body is one region. The linear
    // model has no region terms: nothing is built for it.
    const int volumeRegions = this->Model == MODEL_FIXED_COROTATED ? this->VolumeRegions : VOLUME_NONE;
    if (volumeRegions >= VOLUME_SEGMENTS && repose_vtk::HasWeightArrays(rest->GetPointData()))
    {
      options.volumeRegions = repose::bodySegments(
        repose_vtk::ToSparseWeights(rest->GetPointData(), rest->GetNumberOfPoints()), tets);
      vtkDataArray* labels = rest->GetCellData()->GetArray(repose::arrays::kLabel);
      if (volumeRegions == VOLUME_TISSUES && labels && labels->GetNumberOfTuples() == nt)
      {
        std::vector<int> tetLabels(static_cast<std::size_t>(nt));
        for (vtkIdType c = 0; c < nt; ++c)
        {
          tetLabels[static_cast<std::size_t>(c)] = static_cast<int>(labels->GetTuple1(c));
        }
        // The fold-free continuation's path keeps the segments (see pathVolumeRegions).
        options.pathVolumeRegions = options.volumeRegions;
        options.volumeRegions = repose::tissueSegments(options.volumeRegions, tetLabels);
      }
    }
    else if (volumeRegions != VOLUME_NONE)
    {
      options.volumeRegions.assign(static_cast<std::size_t>(nt), 0);
    }
    const vtkMTimeType restTime = rest->GetMTime();
    if (this->WarmStart && this->Model == MODEL_FIXED_COROTATED && this->LastRestMTime == restTime &&
      this->LastCorrection.size() == 3 * static_cast<std::size_t>(nodes.rows()))
    {
      options.startCorrection =
        Eigen::Map<const repose::Points>(this->LastCorrection.data(), nodes.rows(), 3);
    }
    // Where the solve is, as VTK progress (the fraction is the continuation's path, 0 before it) and
    // text; an observer may call Cancel() from its ProgressEvent.
    auto pathStart = std::chrono::steady_clock::now();  // the continuation's, for its pace
    bool onPath = false;
    options.checkpoint = [this, &pathStart, &onPath](const repose::RelaxationProgress& p) {
      std::string text;
      switch (p.phase)
      {
        case repose::RelaxationProgress::Setup:
          text = "FEM set-up";
          break;
        case repose::RelaxationProgress::Newton:
          text = "Newton step " + std::to_string(p.newtonIterations + 1);
          break;
        case repose::RelaxationProgress::Untangling:
          text = "untangling inverted tets";
          break;
        case repose::RelaxationProgress::Neighbourhood:
          text = "relaxing untangled neighbourhoods";
          break;
        case repose::RelaxationProgress::StrainedRegion:
          text = "relaxing the strained region";
          break;
        case repose::RelaxationProgress::Continuation:
          if (!onPath)
          {
            onPath = true;
            pathStart = std::chrono::steady_clock::now();
          }
          text = "fold-free continuation, step " + std::to_string(p.continuationSteps + 1) + ", " +
            repose::fractionProgressLine("path", p.pathFraction,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - pathStart).count());
          break;
        case repose::RelaxationProgress::Linear:
          text = "linear solve " + std::to_string(p.outerIteration + 1);
          break;
      }
      this->SetProgressText(text.c_str());
      this->UpdateProgress(p.phase == repose::RelaxationProgress::Continuation ? p.pathFraction : 0.0);
      return this->CancelRequested.load();
    };
    const repose::Points input = nodes;
    repose::CorotationalReport report;
    this->LastCorrection.clear();  // a failed run leaves nothing to start from
    repose::relaxCorotational(restNodes, tets, fixedBone, nodes, options, &report);
    this->CancelRequested = false;
    this->SetProgressText(nullptr);  // the executive's own progress events carry none
    this->LastCorrection.resize(3 * static_cast<std::size_t>(nodes.rows()));
    Eigen::Map<repose::Points>(this->LastCorrection.data(), nodes.rows(), 3) = nodes - input;
    this->LastRestMTime = restTime;
    this->WarmStarted = report.correctedStart;

    output->ShallowCopy(posed);
    vtkNew<vtkPoints> points;
    points->SetDataType(posed->GetPoints()->GetDataType());
    points->SetNumberOfPoints(nodes.rows());
    for (vtkIdType v = 0; v < nodes.rows(); ++v)
    {
      points->SetPoint(v, nodes(v, 0), nodes(v, 1), nodes(v, 2));
    }
    output->SetPoints(points);
    this->CGIterations = 0;
    for (int it : report.cgIterations)
    {
      this->CGIterations += it;
    }
    this->NewtonIterations = report.newtonIterations;
    this->RelativeResidual = report.relativeResidual.empty() ? 0.0 : report.relativeResidual.back();
    this->InvertedBefore = report.invertedBefore;
    this->InvertedAfter = report.invertedAfter;
    this->InvertedRigidAfter = report.invertedRigid;
    this->PinchedNodes = report.pinchedNodes;
    this->PinchedShortfall = report.pinchedShortfall;
    this->UntangledNodes = report.untangledNodes;
    this->UntangleNewtonIterations = report.untangleNewtonIterations;
    this->RegionVolumeUpdates = report.regionVolumeUpdates;
    this->LastRelaxTime = report.seconds;
    this->LastAssemblyTime = report.assemblySeconds;
    this->LastSolveTime = report.solveSeconds;
    this->LastUntangleTime = report.untangleSeconds;
    this->ContinuationSteps = report.continuationSteps;
    this->ContinuationUsed = report.continuationUsed;
    this->LastContinuationTime = report.continuationSeconds;
    this->StrainedRegionNodes = report.strainedRegionNodes;
    this->StrainedRegionNewtonIterations = report.strainedRegionNewtonIterations;
    this->LastStrainedRegionTime = report.strainedRegionSeconds;
  }
  catch (const repose::RelaxationCancelled&)
  {
    this->CancelRequested = false;
    this->SetProgressText(nullptr);
    this->Cancelled = true;
    return 0;
  }
  catch (const std::exception& e)
  {
    this->CancelRequested = false;
    this->SetProgressText(nullptr);
    vtkErrorMacro(<< e.what());
    return 0;
  }
  return 1;
}

void vtkReposeCorotationalRelax::Cancel()
{
  this->CancelRequested = true;
}

void vtkReposeCorotationalRelax::ResetCancel()
{
  this->CancelRequested = false;
}

void vtkReposeCorotationalRelax::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "PoissonRatio: " << this->PoissonRatio << "\n";
  os << indent << "OuterIterations: " << this->OuterIterations << "\n";
  os << indent << "Tolerance: " << this->Tolerance << "\n";
  os << indent << "MaxIterations: " << this->MaxIterations << "\n";
  os << indent << "Preconditioner: "
     << (this->Preconditioner == PRECONDITIONER_TWO_LEVEL            ? "TwoLevel"
         : this->Preconditioner == PRECONDITIONER_BLOCK_JACOBI        ? "BlockJacobi"
         : this->Preconditioner == PRECONDITIONER_CHOLMOD             ? "CHOLMOD"
         : this->Preconditioner == PRECONDITIONER_INCOMPLETE_CHOLESKY ? "IncompleteCholesky"
                                                                      : "Jacobi")
     << "\n";
  os << indent << "Model: " << (this->Model == MODEL_FIXED_COROTATED ? "FixedCorotated" : "Linear") << "\n";
  os << indent << "MaxNewtonIterations: " << this->MaxNewtonIterations << "\n";
  os << indent << "UntangleRelaxRings: " << this->UntangleRelaxRings << "\n";
  os << indent << "StrainedRegionThreshold: " << this->StrainedRegionThreshold << "\n";
  os << indent << "StrainedRegionRings: " << this->StrainedRegionRings << "\n";
  os << indent << "StepTolerance: " << this->StepTolerance << "\n";
  os << indent << "EnergyTolerance: " << this->EnergyTolerance << "\n";
  os << indent << "Continuation: " << this->Continuation << "\n";
  os << indent << "SkeletonJSON: " << (this->SkeletonJSON ? "(set)" : "(none)") << "\n";
}
