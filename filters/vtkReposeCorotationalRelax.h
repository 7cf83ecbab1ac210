#ifndef vtkReposeCorotationalRelax_h
#define vtkReposeCorotationalRelax_h
// Refines a skinned tet mesh by a static elastic solve: bone nodes stay at their skinned (rigid)
// positions, the soft tissue settles so that it keeps its volume. MODEL_FIXED_COROTATED (default):
// the nonlinear fixed-corotated energy by projected Newton (removes skinning's inverted tets, keeps
// det F to second order); MODEL_LINEAR: linearized corotational elasticity (Mueller & Gross 2004).
// Input 0: the posed (skinned) mesh, the warm start; input 1: the rest mesh with point data
// "FixedBone" (the stress-free shape and the Dirichlet nodes). Output: input 0 with relaxed points.
// The defaults are the core's (repose::CorotationalOptions), but for VolumeRegions, the filter's own.

#include "ReposeFiltersModule.h"
#include "vtkUnstructuredGridAlgorithm.h"

#include <atomic>

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
  /// The linear solver (repose::CorotationalOptions::Preconditioner, same values): Jacobi-PCG (Eigen),
  /// incomplete-Cholesky PCG, CHOLMOD direct solve, block-Jacobi PCG on float 3x3 blocks, or the same
  /// PCG with a two-level preconditioner (block Jacobi plus rigid-body modes of node aggregates; default).
  enum PreconditionerType
  {
    PRECONDITIONER_JACOBI = 0,
    PRECONDITIONER_INCOMPLETE_CHOLESKY = 1,
    PRECONDITIONER_CHOLMOD = 2,
    PRECONDITIONER_BLOCK_JACOBI = 3,
    PRECONDITIONER_TWO_LEVEL = 4
  };
  vtkSetClampMacro(Preconditioner, int, PRECONDITIONER_JACOBI, PRECONDITIONER_TWO_LEVEL);
  vtkGetMacro(Preconditioner, int);
  void SetPreconditionerToJacobi() { this->SetPreconditioner(PRECONDITIONER_JACOBI); }
  void SetPreconditionerToIncompleteCholesky() { this->SetPreconditioner(PRECONDITIONER_INCOMPLETE_CHOLESKY); }
  void SetPreconditionerToCholmod() { this->SetPreconditioner(PRECONDITIONER_CHOLMOD); }
  void SetPreconditionerToBlockJacobi() { this->SetPreconditioner(PRECONDITIONER_BLOCK_JACOBI); }
  void SetPreconditionerToTwoLevel() { this->SetPreconditioner(PRECONDITIONER_TWO_LEVEL); }
  /// Linear corotational, or fixed-corotated (nonlinear, default; repose::CorotationalOptions::Model).
  enum ModelType
  {
    MODEL_LINEAR = 0,
    MODEL_FIXED_COROTATED = 1
  };
  vtkSetClampMacro(Model, int, MODEL_LINEAR, MODEL_FIXED_COROTATED);
  vtkGetMacro(Model, int);
  void SetModelToLinear() { this->SetModel(MODEL_LINEAR); }
  void SetModelToFixedCorotated() { this->SetModel(MODEL_FIXED_COROTATED); }
  /// Fixed-corotated model: at most this many Newton iterations (default 60), stopping once no node moves more
  /// than StepTolerance times the mean rest edge length in an iteration (default 0.01).
  vtkSetClampMacro(MaxNewtonIterations, int, 1, 10000);
  vtkGetMacro(MaxNewtonIterations, int);
  vtkSetClampMacro(StepTolerance, double, 1e-12, 1.0);
  vtkGetMacro(StepTolerance, double);
  /// Fixed-corotated model: also stops when an iteration lowers the energy by less than this fraction (default 1e-3).
  vtkSetClampMacro(EnergyTolerance, double, 0.0, 1.0);
  vtkGetMacro(EnergyTolerance, double);
  /// Fixed-corotated model: regions whose volume is held as a whole (see
  /// repose::CorotationalOptions::volumeRegions), against the volumetric locking of linear tets.
  /// NONE: the paper's solve; BODY: the whole body; SEGMENTS (default): body segments, each tet in the
  /// segment of the bone with the largest summed weight over its nodes (needs the rest mesh's Weights
  /// and BoneIds; falls back to BODY without them); TISSUES: segments split by the tets' cell data
  /// Label, so each organ keeps its own volume within its segment (falls back to SEGMENTS without
  /// Label). Slower, and the fold-free continuation can stall with it.
  enum VolumeRegionsType
  {
    VOLUME_NONE = 0,
    VOLUME_BODY = 1,
    VOLUME_SEGMENTS = 2,
    VOLUME_TISSUES = 3
  };
  vtkSetClampMacro(VolumeRegions, int, VOLUME_NONE, VOLUME_TISSUES);
  vtkGetMacro(VolumeRegions, int);
  void SetVolumeRegionsToNone() { this->SetVolumeRegions(VOLUME_NONE); }
  void SetVolumeRegionsToBody() { this->SetVolumeRegions(VOLUME_BODY); }
  void SetVolumeRegionsToSegments() { this->SetVolumeRegions(VOLUME_SEGMENTS); }
  void SetVolumeRegionsToTissues() { this->SetVolumeRegions(VOLUME_TISSUES); }
  /// Fixed-corotated model: a region's volume stiffness, in units of the tissue's Lame lambda.
  vtkSetClampMacro(RegionVolumeStiffness, double, 0.0, 1e6);
  vtkGetMacro(RegionVolumeStiffness, double);
  /// Fixed-corotated model: each region's volume is then held to this relative tolerance by up to 4 multiplier
  /// updates (see repose::CorotationalOptions::regionVolumeTolerance); 1 or more: the penalty alone.
  vtkSetClampMacro(RegionVolumeTolerance, double, 0.0, 1.0);
  vtkGetMacro(RegionVolumeTolerance, double);
  /// Fixed-corotated model: the log barrier that keeps the tets positive when Newton starts from folding (default
  /// on; see repose::CorotationalOptions::inversionBarrier). Off: only the finite penalty, about
  /// twice as fast on the medium phantom, but Newton may stall short of the minimum.
  vtkSetMacro(InversionBarrier, bool);
  vtkGetMacro(InversionBarrier, bool);
  vtkBooleanMacro(InversionBarrier, bool);
  /// Fixed-corotated model: after an untangling round, the moved nodes and this many rings of neighbours are
  /// relaxed on their own, then the whole mesh once (default 2; see
  /// repose::CorotationalOptions::untangleRelaxRings). -1: the whole mesh after every round.
  vtkSetClampMacro(UntangleRelaxRings, int, -1, 1000);
  vtkGetMacro(UntangleRelaxRings, int);
  /// Fixed-corotated model, from a cold start: the tets strained by skinning above this threshold (strain energy
  /// density over the shear modulus), their free nodes and StrainedRegionRings rings of neighbours
  /// are relaxed on their own before the whole mesh (default 1e-4, rings 3; see
  /// repose::CorotationalOptions::strainedRegionThreshold). 0: the whole mesh at once.
  vtkSetClampMacro(StrainedRegionThreshold, double, 0.0, 1e30);
  vtkGetMacro(StrainedRegionThreshold, double);
  vtkSetClampMacro(StrainedRegionRings, int, 0, 1000);
  vtkGetMacro(StrainedRegionRings, int);
  /// Fixed-corotated model with the barrier: when the solve leaves a fold (inverted tets with a free
  /// node), solve again by a fold-free continuation from the rest shape (see
  /// repose::CorotationalOptions::continuation, same values): never, if tets stay inverted and no node
  /// is pinched between bones (default; see GetPinchedNodes), or always.
  enum ContinuationType
  {
    CONTINUATION_NEVER = 0,
    CONTINUATION_IF_INVERTED = 1,
    CONTINUATION_ALWAYS = 2
  };
  vtkSetClampMacro(Continuation, int, CONTINUATION_NEVER, CONTINUATION_ALWAYS);
  vtkGetMacro(Continuation, int);
  void SetContinuationToNever() { this->SetContinuation(CONTINUATION_NEVER); }
  void SetContinuationToIfInverted() { this->SetContinuation(CONTINUATION_IF_INVERTED); }
  void SetContinuationToAlways() { this->SetContinuation(CONTINUATION_ALWAYS); }
  /// Optional: the skeleton (as for vtkReposeSkinning), whose hierarchy the continuation's bone
  /// paths follow so that joints stay together along them. Without it each bone moves on its own.
  vtkSetStringMacro(SkeletonJSON);
  vtkGetStringMacro(SkeletonJSON);
  /// Fixed-corotated model: start from the last execution's correction, the input plus (last output - last input)
  /// on the free nodes, when the rest mesh is the same and that start has no more inverted tets
  /// than the input (see repose::CorotationalOptions::startCorrection). For animation frames and
  /// drags: a few Newton steps from next to the minimum, and consecutive results stay coherent.
  /// Off (default): every pose is solved from the skinned input alone.
  vtkSetMacro(WarmStart, bool);
  vtkGetMacro(WarmStart, bool);
  vtkBooleanMacro(WarmStart, bool);

  /// The words users type for a setting ("model", "volume" or "continuation": the CLI's
  /// --relax-model, --relax-volume and --relax-continuation, a batch manifest's relax entries), in
  /// the order messages list them, and the value each stands for (SetModel, SetVolumeRegions,
  /// SetContinuation); GetWord: nullptr out of range; GetWordValue: -1 for another word.
  static int GetNumberOfWords(const char* setting);
  static const char* GetWord(const char* setting, int i);
  static int GetWordValue(const char* setting, const char* word);

  void SetRestMeshConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }
  void SetRestMeshData(vtkDataObject* mesh) { this->SetInputData(1, mesh); }

  /// Figures of the last execution.
  vtkGetMacro(CGIterations, int);          ///< summed over outer (or Newton) iterations
  vtkGetMacro(NewtonIterations, int);      ///< fixed-corotated model; 0 for linear
  vtkGetMacro(RelativeResidual, double);   ///< of the last outer iteration
  vtkGetMacro(InvertedBefore, int);
  vtkGetMacro(InvertedAfter, int);
  /// Inverted tets after relaxing whose nodes are all fixed to bones (no free node can repair them).
  vtkGetMacro(InvertedRigidAfter, int);
  /// Free nodes of the result pinched between bones: no position keeps all their bone-face tets
  /// positive, so no solve can remove those folds (bones pressed into each other), and the fold-free
  /// continuation (Continuation 1) is not run for them. The shortfall: how far the worst of them stays
  /// on the wrong side of a bone face, in the mesh's units.
  vtkGetMacro(PinchedNodes, int);
  vtkGetMacro(PinchedShortfall, double);
  /// Node moves made by the untangling step (0 when the solve left nothing inverted).
  vtkGetMacro(UntangledNodes, int);
  /// Newton iterations of the neighbourhood solves after untangling (not in GetNewtonIterations()).
  vtkGetMacro(UntangleNewtonIterations, int);
  /// Unknowns and Newton iterations of the strained region's solve (0: it did not run; its
  /// iterations are not in GetNewtonIterations()).
  vtkGetMacro(StrainedRegionNodes, int);
  vtkGetMacro(StrainedRegionNewtonIterations, int);
  /// Region-volume multiplier updates made (see RegionVolumeTolerance).
  vtkGetMacro(RegionVolumeUpdates, int);
  /// Steps of the fold-free continuation (0: it did not run), and whether its result was kept.
  vtkGetMacro(ContinuationSteps, int);
  vtkGetMacro(ContinuationUsed, bool);
  /// Whether the last execution started from the previous correction (see WarmStart).
  vtkGetMacro(WarmStarted, bool);
  vtkGetMacro(LastRelaxTime, double);
  /// Parts of LastRelaxTime: Hessian assembly, linear solves (CG or CHOLMOD), untangling.
  vtkGetMacro(LastAssemblyTime, double);
  vtkGetMacro(LastSolveTime, double);
  vtkGetMacro(LastUntangleTime, double);
  vtkGetMacro(LastContinuationTime, double);  ///< includes its assembly and solves
  vtkGetMacro(LastStrainedRegionTime, double); ///< includes its assembly and solves

  /// While it runs, the solve reports where it is at each check as VTK progress: ProgressEvent, with
  /// GetProgressText() "FEM set-up", "relaxing the strained region", "Newton step N", "untangling
  /// inverted tets", "relaxing untangled neighbourhoods", "fold-free continuation, step N, path P %" or "linear solve N", and GetProgress()
  /// the continuation's path fraction (0 before it). A ProgressEvent observer may call Cancel().
  ///
  /// Stops the running execution (or, if none runs, the next one) at its next check: between Newton
  /// steps, continuation steps and untangling rounds, a few seconds apart at most on a 2.7 M-tet
  /// mesh. That execution fails (the executive says so; the filter adds no error of its own), leaves
  /// no output and reports GetCancelled(); the next one runs normally. Safe to call from another
  /// thread (a GUI's Cancel button; not a Python thread: VTK 9.1's wrapping keeps Python's global lock
  /// during Update()).
  void Cancel();
  /// Forgets a Cancel() that no execution has taken yet (one that came just after the solve's last
  /// check), so that it does not stop the next execution.
  void ResetCancel();
  /// Whether the last execution was stopped by Cancel().
  vtkGetMacro(Cancelled, bool);

protected:
  vtkReposeCorotationalRelax();
  ~vtkReposeCorotationalRelax() override;
  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  // The solver's options: the constructor gives them the core's defaults.
  double PoissonRatio;
  int OuterIterations;
  double Tolerance;
  int MaxIterations;
  int Preconditioner;
  int Model;
  int MaxNewtonIterations;
  double StepTolerance;
  double EnergyTolerance;
  int VolumeRegions = VOLUME_SEGMENTS;
  double RegionVolumeStiffness;
  double RegionVolumeTolerance;
  int RegionVolumeUpdates = 0;
  bool InversionBarrier;
  int UntangleRelaxRings;
  double StrainedRegionThreshold;
  int StrainedRegionRings;
  int StrainedRegionNodes = 0;
  int StrainedRegionNewtonIterations = 0;
  double LastStrainedRegionTime = 0.0;
  int Continuation;
  char* SkeletonJSON = nullptr;
  bool WarmStart = false;
  bool WarmStarted = false;
  int ContinuationSteps = 0;
  bool ContinuationUsed = false;
  std::atomic<bool> CancelRequested{ false };
  bool Cancelled = false;
  double LastContinuationTime = 0.0;
  int CGIterations = 0;
  int NewtonIterations = 0;
  double RelativeResidual = 0;
  int InvertedBefore = 0;
  int InvertedAfter = 0;
  int InvertedRigidAfter = 0;
  int PinchedNodes = 0;
  double PinchedShortfall = 0.0;
  int UntangledNodes = 0;
  int UntangleNewtonIterations = 0;
  double LastAssemblyTime = 0.0;
  double LastSolveTime = 0.0;
  double LastUntangleTime = 0.0;
  double LastRelaxTime = 0;

private:
  struct Internals; // the core's options and report, and the warm start kept between runs
  Internals* Internal;

  vtkReposeCorotationalRelax(const vtkReposeCorotationalRelax&) = delete;
  void operator=(const vtkReposeCorotationalRelax&) = delete;
};

#endif
