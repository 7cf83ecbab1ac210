#ifndef vtkReposeCorotationalRelax_h
#define vtkReposeCorotationalRelax_h
// Refines a skinned tet mesh by a static elastic solve: bone nodes stay at their skinned (rigid)
// positions, the soft tissue settles so that it keeps its volume. Model 1 (default): the nonlinear
// fixed-corotated energy by projected Newton (removes skinning's inverted tets, keeps det F to
// second order); model 0: linearized corotational elasticity (Mueller & Gross 2004). Input 0: the posed (skinned) mesh, the warm start; input 1: the rest mesh with point data
// "FixedBone" (the stress-free shape and the Dirichlet nodes). Output: input 0 with relaxed points.

#include "ReposeFiltersModule.h"
#include "vtkUnstructuredGridAlgorithm.h"

#include <atomic>
#include <vector>

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
  /// 0 = Jacobi-PCG (Eigen), 1 = incomplete-Cholesky PCG, 2 = CHOLMOD direct solve,
  /// 3 = block-Jacobi PCG on float 3x3 blocks, 4 = the same PCG with a two-level preconditioner
  /// (block Jacobi plus rigid-body modes of node aggregates; default).
  vtkSetClampMacro(Preconditioner, int, 0, 4);
  vtkGetMacro(Preconditioner, int);
  /// 0 = linear corotational, 1 = fixed-corotated (nonlinear, default).
  vtkSetClampMacro(Model, int, 0, 1);
  vtkGetMacro(Model, int);
  /// Model 1: at most this many Newton iterations (default 60), stopping once no node moves more
  /// than StepTolerance times the mean rest edge length in an iteration (default 0.01).
  vtkSetClampMacro(MaxNewtonIterations, int, 1, 10000);
  vtkGetMacro(MaxNewtonIterations, int);
  vtkSetClampMacro(StepTolerance, double, 1e-12, 1.0);
  vtkGetMacro(StepTolerance, double);
  /// Model 1: also stops when an iteration lowers the energy by less than this fraction (default 1e-3).
  vtkSetClampMacro(EnergyTolerance, double, 0.0, 1.0);
  vtkGetMacro(EnergyTolerance, double);
  /// Model 1: regions whose volume is held as a whole (see repose::CorotationalOptions::volumeRegions),
  /// against the volumetric locking of linear tets. 0: none (the paper's solve); 1: the whole body;
  /// 2 (default): body segments, each tet in the segment of the bone with the largest summed weight
  /// over its nodes (needs the rest mesh's Weights and BoneIds; falls back to 1 without them);
  /// 3: segments split by the tets' cell data Label, so each organ keeps its own volume within its
  /// segment (falls back to 2 without Label). Slower, and the fold-free continuation can stall with
  /// it (tiny phantom's test pose: 170 steps, not kept, where segments complete in 29).
  vtkSetClampMacro(VolumeRegions, int, 0, 3);
  vtkGetMacro(VolumeRegions, int);
  /// Model 1: a region's volume stiffness, in units of the tissue's Lame lambda.
  vtkSetClampMacro(RegionVolumeStiffness, double, 0.0, 1e6);
  vtkGetMacro(RegionVolumeStiffness, double);
  /// Model 1: each region's volume is then held to this relative tolerance by up to 4 multiplier
  /// updates (see repose::CorotationalOptions::regionVolumeTolerance); 1 or more: the penalty alone.
  vtkSetClampMacro(RegionVolumeTolerance, double, 0.0, 1.0);
  vtkGetMacro(RegionVolumeTolerance, double);
  /// Model 1: the log barrier that keeps the tets positive when Newton starts from folding (default
  /// on; see repose::CorotationalOptions::inversionBarrier). Off: only the finite penalty, about
  /// twice as fast on the medium phantom, but Newton may stall short of the minimum.
  vtkSetMacro(InversionBarrier, bool);
  vtkGetMacro(InversionBarrier, bool);
  vtkBooleanMacro(InversionBarrier, bool);
  /// Model 1: after an untangling round, the moved nodes and this many rings of neighbours are
  /// relaxed on their own, then the whole mesh once (default 2; see
  /// repose::CorotationalOptions::untangleRelaxRings). -1: the whole mesh after every round.
  vtkSetClampMacro(UntangleRelaxRings, int, -1, 1000);
  vtkGetMacro(UntangleRelaxRings, int);
  /// Model 1, from a cold start: the tets strained by skinning above this threshold (strain energy
  /// density over the shear modulus), their free nodes and StrainedRegionRings rings of neighbours
  /// are relaxed on their own before the whole mesh (default 1e-4, rings 3; see
  /// repose::CorotationalOptions::strainedRegionThreshold). 0: the whole mesh at once.
  vtkSetClampMacro(StrainedRegionThreshold, double, 0.0, 1e30);
  vtkGetMacro(StrainedRegionThreshold, double);
  vtkSetClampMacro(StrainedRegionRings, int, 0, 1000);
  vtkGetMacro(StrainedRegionRings, int);
  /// Model 1 with the barrier: when the solve leaves a fold (inverted tets with a free node), solve
  /// again by a fold-free continuation from the rest shape (see
  /// repose::CorotationalOptions::continuation). 0: never, 1: if tets stay inverted and no node is
  /// pinched between bones (default; see GetPinchedNodes), 2: always.
  vtkSetClampMacro(Continuation, int, 0, 2);
  vtkGetMacro(Continuation, int);
  /// Optional: the skeleton (as for vtkReposeSkinning), whose hierarchy the continuation's bone
  /// paths follow so that joints stay together along them. Without it each bone moves on its own.
  vtkSetStringMacro(SkeletonJSON);
  vtkGetStringMacro(SkeletonJSON);
  /// Model 1: start from the last execution's correction, the input plus (last output - last input)
  /// on the free nodes, when the rest mesh is the same and that start has no more inverted tets
  /// than the input (see repose::CorotationalOptions::startCorrection). For animation frames and
  /// drags: a few Newton steps from next to the minimum, and consecutive results stay coherent.
  /// Off (default): every pose is solved from the skinned input alone.
  vtkSetMacro(WarmStart, bool);
  vtkGetMacro(WarmStart, bool);
  vtkBooleanMacro(WarmStart, bool);

  void SetRestMeshConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }
  void SetRestMeshData(vtkDataObject* mesh) { this->SetInputData(1, mesh); }

  /// Figures of the last execution.
  vtkGetMacro(CGIterations, int);          ///< summed over outer (or Newton) iterations
  vtkGetMacro(NewtonIterations, int);      ///< model 1; 0 for model 0
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

  double PoissonRatio = 0.49;
  int OuterIterations = 1;
  double Tolerance = 1e-6;
  int MaxIterations = 2000;
  int Preconditioner = 4;
  int Model = 1;
  int MaxNewtonIterations = 60;
  double StepTolerance = 0.01;
  double EnergyTolerance = 1e-3;
  int VolumeRegions = 2;
  double RegionVolumeStiffness = 30.0;
  double RegionVolumeTolerance = 1e-5;
  int RegionVolumeUpdates = 0;
  bool InversionBarrier = true;
  int UntangleRelaxRings = 2;
  double StrainedRegionThreshold = 1e-4;
  int StrainedRegionRings = 3;
  int StrainedRegionNodes = 0;
  int StrainedRegionNewtonIterations = 0;
  double LastStrainedRegionTime = 0.0;
  int Continuation = 1;
  char* SkeletonJSON = nullptr;
  bool WarmStart = false;
  bool WarmStarted = false;
  std::vector<double> LastCorrection;  // last output - last input, 3 per node
  vtkMTimeType LastRestMTime = 0;   // ... for this rest mesh
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
  vtkReposeCorotationalRelax(const vtkReposeCorotationalRelax&) = delete;
  void operator=(const vtkReposeCorotationalRelax&) = delete;
};

#endif
