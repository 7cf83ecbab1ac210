#include "vtkReposeCorotationalRelax.h"

#include <stdexcept>
#include <string>
#include <vector>

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
#include "vtkSmartPointer.h"
#include "vtkUnstructuredGrid.h"

#include <exception>

#include "ReposeMeshConversion.h"
#include "ReposeWeightArrays.h"
#include "array_names.h"
#include "corotational_fem.h"
#include "relaxation_progress_text.h"
#include "relaxation_words.h"
#include "skeleton.h"
#include "skinned_relaxation.h"

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
using Regions = repose::VolumeRegionChoice;
static_assert(SameValue(Relax::VOLUME_NONE, int(Regions::None)) &&
  SameValue(Relax::VOLUME_BODY, int(Regions::Body)) &&
  SameValue(Relax::VOLUME_SEGMENTS, int(Regions::Segments)) &&
  SameValue(Relax::VOLUME_TISSUES, int(Regions::Tissues)));
}

struct vtkReposeCorotationalRelax::Internals
{
  repose::RelaxationWarmStart WarmStart; // the last run's correction
  static repose::CorotationalOptions Options(vtkReposeCorotationalRelax* self);
  static void StoreReport(vtkReposeCorotationalRelax* self, const repose::CorotationalReport& report);
};

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
  this->Internal = new Internals;
}

vtkReposeCorotationalRelax::~vtkReposeCorotationalRelax()
{
  delete this->Internal;
  this->SetSkeletonJSON(nullptr);
}

int vtkReposeCorotationalRelax::FillInputPortInformation(int port, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkUnstructuredGrid");
  (void)port;
  return 1;
}

namespace
{
/// The rest mesh as the core reads it. Throws std::invalid_argument for a cell that is not a tet.
repose::RelaxationRestMesh ToRestMesh(vtkUnstructuredGrid* rest, vtkDataArray* fixed, bool needWeights,
  repose::SparseWeights& weights)
{
  repose::RelaxationRestMesh mesh;
  const vtkIdType nt = rest->GetNumberOfCells();
  mesh.tets.resize(nt, 4);
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < nt; ++c)
  {
    rest->GetCellPoints(c, ids);
    if (ids->GetNumberOfIds() != 4)
    {
      throw std::invalid_argument("cell " + std::to_string(c) + " of the rest mesh is not a tetrahedron");
    }
    for (int k = 0; k < 4; ++k)
    {
      mesh.tets(c, k) = static_cast<int>(ids->GetId(k));
    }
  }
  mesh.fixedBone = repose_vtk::ToInts(fixed);
  mesh.nodes = repose_vtk::ToPoints(rest->GetPoints());
  if (needWeights && repose_vtk::HasWeightArrays(rest->GetPointData()))
  {
    weights = repose_vtk::ToSparseWeights(rest->GetPointData(), rest->GetNumberOfPoints());
    mesh.weights = &weights;
  }
  vtkDataArray* labels = rest->GetCellData()->GetArray(repose::arrays::kLabel);
  if (labels && labels->GetNumberOfTuples() == nt)
  {
    mesh.tetLabels = repose_vtk::ToInts(labels);
  }
  mesh.key = rest->GetMTime();
  return mesh;
}
}

repose::CorotationalOptions vtkReposeCorotationalRelax::Internals::Options(vtkReposeCorotationalRelax* self)
{
  repose::CorotationalOptions options;
  options.poisson = self->PoissonRatio;
  options.outerIterations = self->OuterIterations;
  options.tolerance = self->Tolerance;
  options.maxCgIterations = self->MaxIterations;
  options.preconditioner = static_cast<repose::CorotationalOptions::Preconditioner>(self->Preconditioner);
  options.model = static_cast<repose::CorotationalOptions::Model>(self->Model);
  options.maxNewtonIterations = self->MaxNewtonIterations;
  options.stepTolerance = self->StepTolerance;
  options.energyTolerance = self->EnergyTolerance;
  options.regionVolumeStiffness = self->RegionVolumeStiffness;
  options.regionVolumeTolerance = self->RegionVolumeTolerance;
  options.inversionBarrier = self->InversionBarrier;
  options.untangleRelaxRings = self->UntangleRelaxRings;
  options.strainedRegionThreshold = self->StrainedRegionThreshold;
  options.strainedRegionRings = self->StrainedRegionRings;
  options.continuation = static_cast<repose::CorotationalOptions::Continuation>(self->Continuation);
  if (self->SkeletonJSON && *self->SkeletonJSON)
  {
    for (const repose::Joint& joint : repose::parseSkeletonJson(self->SkeletonJSON).joints)
    {
      options.boneParents.push_back(joint.parent);
    }
  }
  // Where the solve is, as VTK progress (the fraction is the continuation's path, 0 before it) and
  // text; an observer may call Cancel() from its ProgressEvent.
  options.checkpoint = [self, text = repose::RelaxationProgressText()](
                         const repose::RelaxationProgress& p) mutable {
    self->SetProgressText(text(p).c_str());
    self->UpdateProgress(p.phase == repose::RelaxationProgress::Continuation ? p.pathFraction : 0.0);
    return self->CancelRequested.load();
  };
  return options;
}

void vtkReposeCorotationalRelax::Internals::StoreReport(
  vtkReposeCorotationalRelax* self, const repose::CorotationalReport& report)
{
  self->WarmStarted = report.correctedStart;
  self->CGIterations = 0;
  for (int it : report.cgIterations)
  {
    self->CGIterations += it;
  }
  self->NewtonIterations = report.newtonIterations;
  self->RelativeResidual = report.relativeResidual.empty() ? 0.0 : report.relativeResidual.back();
  self->InvertedBefore = report.invertedBefore;
  self->InvertedAfter = report.invertedAfter;
  self->InvertedRigidAfter = report.invertedRigid;
  self->PinchedNodes = report.pinchedNodes;
  self->PinchedShortfall = report.pinchedShortfall;
  self->UntangledNodes = report.untangledNodes;
  self->UntangleNewtonIterations = report.untangleNewtonIterations;
  self->RegionVolumeUpdates = report.regionVolumeUpdates;
  self->LastRelaxTime = report.seconds;
  self->LastAssemblyTime = report.assemblySeconds;
  self->LastSolveTime = report.solveSeconds;
  self->LastUntangleTime = report.untangleSeconds;
  self->ContinuationSteps = report.continuationSteps;
  self->ContinuationUsed = report.continuationUsed;
  self->LastContinuationTime = report.continuationSeconds;
  self->StrainedRegionNodes = report.strainedRegionNodes;
  self->StrainedRegionNewtonIterations = report.strainedRegionNewtonIterations;
  self->LastStrainedRegionTime = report.strainedRegionSeconds;
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
    repose::SparseWeights weights;
    // The weights only for the segments (the linear model has no regions).
    const bool segments = this->Model == MODEL_FIXED_COROTATED && this->VolumeRegions >= VOLUME_SEGMENTS;
    const repose::RelaxationRestMesh restMesh = ToRestMesh(rest, fixed, segments, weights);
    repose::Points nodes = repose_vtk::ToPoints(posed->GetPoints());
    repose::CorotationalReport report;
    repose::relaxSkinnedMesh(restMesh, static_cast<repose::VolumeRegionChoice>(this->VolumeRegions),
      Internals::Options(this), this->WarmStart, this->Internal->WarmStart, nodes, &report);
    this->CancelRequested = false;
    this->SetProgressText(nullptr); // the executive's own progress events carry none
    Internals::StoreReport(this, report);
    output->ShallowCopy(posed);
    output->SetPoints(repose_vtk::ToPoints(nodes, posed->GetPoints()->GetDataType()));
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

int vtkReposeCorotationalRelax::GetNumberOfWords(const char* setting)
{
  return setting ? static_cast<int>(repose::relaxationWords(setting).size()) : 0;
}

const char* vtkReposeCorotationalRelax::GetWord(const char* setting, int i)
{
  return i >= 0 && i < GetNumberOfWords(setting) ? repose::relaxationWords(setting)[i].word : nullptr;
}

int vtkReposeCorotationalRelax::GetWordValue(const char* setting, const char* word)
{
  return setting && word ? repose::relaxationWordValue(setting, word) : -1;
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
