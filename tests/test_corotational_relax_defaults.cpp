// vtkReposeCorotationalRelax solves with the core's defaults (one source of them) and names the
// core's enum values: a default or an enum value changed on one side only fails here.
#include <gtest/gtest.h>

#include <vector>

#include <vtkNew.h>

#include "corotational_fem.h"
#include "vtkReposeCorotationalRelax.h"

using repose::CorotationalOptions;

TEST(CorotationalRelaxDefaults, FilterDefaultsAreTheCores) {
  vtkNew<vtkReposeCorotationalRelax> filter;
  const CorotationalOptions core;
  EXPECT_EQ(filter->GetPoissonRatio(), core.poisson);
  EXPECT_EQ(filter->GetOuterIterations(), core.outerIterations);
  EXPECT_EQ(filter->GetTolerance(), core.tolerance);
  EXPECT_EQ(filter->GetMaxIterations(), core.maxCgIterations);
  EXPECT_EQ(filter->GetPreconditioner(), int(core.preconditioner));
  EXPECT_EQ(filter->GetModel(), int(core.model));
  EXPECT_EQ(filter->GetMaxNewtonIterations(), core.maxNewtonIterations);
  EXPECT_EQ(filter->GetStepTolerance(), core.stepTolerance);
  EXPECT_EQ(filter->GetEnergyTolerance(), core.energyTolerance);
  EXPECT_EQ(filter->GetRegionVolumeStiffness(), core.regionVolumeStiffness);
  EXPECT_EQ(filter->GetRegionVolumeTolerance(), core.regionVolumeTolerance);
  EXPECT_EQ(filter->GetInversionBarrier(), core.inversionBarrier);
  EXPECT_EQ(filter->GetUntangleRelaxRings(), core.untangleRelaxRings);
  EXPECT_EQ(filter->GetStrainedRegionThreshold(), core.strainedRegionThreshold);
  EXPECT_EQ(filter->GetStrainedRegionRings(), core.strainedRegionRings);
  EXPECT_EQ(filter->GetContinuation(), int(core.continuation));
  EXPECT_FALSE(filter->GetWarmStart());
  // The filter's own setting (the core takes regions per tet): body segments.
  EXPECT_EQ(filter->GetVolumeRegions(), vtkReposeCorotationalRelax::VOLUME_SEGMENTS);
}

// The solve the CLI, the GUI and Python get unless told otherwise.
TEST(CorotationalRelaxDefaults, CoreDefaultsAreTheNonlinearSolve) {
  const CorotationalOptions core;
  EXPECT_EQ(core.model, CorotationalOptions::FixedCorotated);
  EXPECT_EQ(core.preconditioner, CorotationalOptions::TwoLevel);
  EXPECT_EQ(core.continuation, CorotationalOptions::IfInverted);
  EXPECT_EQ(core.poisson, 0.49);
  EXPECT_EQ(core.stepTolerance, 0.01);
  EXPECT_EQ(core.energyTolerance, 1e-3);
}

TEST(CorotationalRelaxDefaults, NamedSettersSetTheCoresValues) {
  using R = vtkReposeCorotationalRelax;
  struct Named {
    void (R::*set)();
    int (R::*get)();
    int value;
  };
  const std::vector<Named> named = {
      {&R::SetModelToLinear, &R::GetModel, CorotationalOptions::Linear},
      {&R::SetModelToFixedCorotated, &R::GetModel, CorotationalOptions::FixedCorotated},
      {&R::SetContinuationToNever, &R::GetContinuation, CorotationalOptions::Never},
      {&R::SetContinuationToAlways, &R::GetContinuation, CorotationalOptions::Always},
      {&R::SetContinuationToIfInverted, &R::GetContinuation, CorotationalOptions::IfInverted},
      {&R::SetPreconditionerToJacobi, &R::GetPreconditioner, CorotationalOptions::Jacobi},
      {&R::SetPreconditionerToIncompleteCholesky, &R::GetPreconditioner, CorotationalOptions::IncompleteCholesky},
      {&R::SetPreconditionerToCholmod, &R::GetPreconditioner, CorotationalOptions::Cholmod},
      {&R::SetPreconditionerToBlockJacobi, &R::GetPreconditioner, CorotationalOptions::BlockJacobi},
      {&R::SetPreconditionerToTwoLevel, &R::GetPreconditioner, CorotationalOptions::TwoLevel},
      {&R::SetVolumeRegionsToNone, &R::GetVolumeRegions, R::VOLUME_NONE},
      {&R::SetVolumeRegionsToBody, &R::GetVolumeRegions, R::VOLUME_BODY},
      {&R::SetVolumeRegionsToTissues, &R::GetVolumeRegions, R::VOLUME_TISSUES},
      {&R::SetVolumeRegionsToSegments, &R::GetVolumeRegions, R::VOLUME_SEGMENTS},
  };
  vtkNew<R> f;
  for (std::size_t i = 0; i < named.size(); ++i) {
    (f.Get()->*named[i].set)();
    EXPECT_EQ((f.Get()->*named[i].get)(), named[i].value) << "setter " << i;
  }
  // Out of range is clamped to the nearest choice, as VTK's clamp macros do.
  f->SetModel(7);
  EXPECT_EQ(f->GetModel(), R::MODEL_FIXED_COROTATED);
}
