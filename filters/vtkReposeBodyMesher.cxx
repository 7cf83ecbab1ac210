#include "vtkReposeBodyMesher.h"

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkCellType.h"
#include "vtkDataArray.h"
#include "vtkIdTypeArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkMatrix3x3.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkReposeSurfaceExtractor.h"
#include "ReposeImageConversion.h"
#include "ReposeMeshConversion.h"
#include "vtkSmartPointer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <stdexcept>
#include <sstream>

#include "mesh_budget.h"
#include "meshing_mask.h"
#include "image_grid.h"
#include "mesh_ordering.h"
#include "mesh_tagging.h"
#include "skeleton.h"
#include "tet_mesher.h"
#include "array_names.h"

vtkStandardNewMacro(vtkReposeBodyMesher);

namespace
{
using Clock = std::chrono::steady_clock;
double SecondsSince(Clock::time_point t)
{
  return std::chrono::duration<double>(Clock::now() - t).count();
}


// Triangle surface -> core arrays; false when a cell is not a triangle.
bool ToTriangles(vtkPolyData* surface, repose::Points& V, repose::Triangles& F)
{
  V = repose_vtk::ToPoints(surface->GetPoints());
  vtkCellArray* polys = surface->GetPolys();
  F.resize(polys->GetNumberOfCells(), 3);
  vtkIdType row = 0;
  vtkIdType npts;
  const vtkIdType* pts;
  for (polys->InitTraversal(); polys->GetNextCell(npts, pts); ++row)
  {
    if (npts != 3)
    {
      return false;
    }
    F.row(row) << int(pts[0]), int(pts[1]), int(pts[2]);
  }
  return surface->GetNumberOfCells() == polys->GetNumberOfCells();
}
}

vtkReposeBodyMesher::vtkReposeBodyMesher()
{
  this->SetNumberOfInputPorts(2);
}

int vtkReposeBodyMesher::FillInputPortInformation(int port, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkImageData");
  if (port == 1)
  {
    info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  }
  return 1;
}

void vtkReposeBodyMesher::SetIntensityData(vtkImageData* image)
{
  this->SetInputData(1, image);
}

int vtkReposeBodyMesher::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  const auto start = Clock::now();
  this->NumberOfNodes = this->NumberOfTets = this->NumberOfSurfaceTriangles = 0;
  this->NumberOfSeedPoints = this->NumberOfFixedNodes = this->NumberOfFreedContactNodes = 0;
  this->NumberOfContactVoxelsCut = 0;
  this->MeshingSpacingUsed = 0;
  this->ContactReport.clear();
  this->TotalSeconds = this->TetGenSeconds = 0;
  this->Report.clear();

  vtkImageData* labelImage = vtkImageData::GetData(inputVector[0]);
  vtkImageData* intensityImage =
    inputVector[1]->GetNumberOfInformationObjects() > 0 ? vtkImageData::GetData(inputVector[1]) : nullptr;
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  if (!labelImage || !labelImage->GetPointData()->GetScalars())
  {
    vtkErrorMacro("the label image (input 0) has no scalars");
    return 0;
  }
  if (this->SkeletonJSON.empty())
  {
    vtkErrorMacro("SkeletonJSON is empty: the bones (and so the fixed nodes) come from the skeleton");
    return 0;
  }
  std::ostringstream report;
  try
  {
    auto t = Clock::now();
    repose::LabelVolume labels;
    if (!repose_vtk::ToVolume(labelImage, labels))
    {
      vtkErrorMacro("the label image must have one scalar component per voxel");
      return 0;
    }
    repose::IntensityVolume intensity;
    if (intensityImage && !repose_vtk::ToVolume(intensityImage, intensity))
    {
      vtkErrorMacro("the intensity image (input 1) must have one scalar component per voxel");
      return 0;
    }
    const repose::Skeleton skeleton = repose::parseSkeletonJson(this->SkeletonJSON);
    const int maxLabel = labels.data.empty() ? 0 : *std::max_element(labels.data.begin(), labels.data.end());
    const std::vector<int> boneOfLabel = repose::boneOfLabel(skeleton, std::max(0, maxLabel));
    report << "input: " << labels.grid.dims[0] << "x" << labels.grid.dims[1] << "x" << labels.grid.dims[2]
           << " voxels, spacing " << labels.grid.spacing.transpose() << " mm, " << skeleton.size()
           << " joints" << (intensityImage ? ", with intensity image" : "") << " (" << SecondsSince(t)
           << " s)\n";

    repose::MeshingMaskOptions maskOptions;
    maskOptions.body.bodyThreshold = this->BodyThreshold;
    maskOptions.meshSpacingMm = this->MeshingSpacing;
    maskOptions.maxTets = static_cast<double>(this->MaxTets);
    maskOptions.skinLabels = this->SkinLabels;
    maskOptions.peelOuterLayer = this->PeelOuterLayer;
    maskOptions.separateContacts = this->SeparateContacts;
    repose::TetMeshingOptions meshOptions;
    meshOptions.radiusEdgeRatio = this->RadiusEdgeRatio;
    meshOptions.maxTetVolume = this->MaxTetVolume;
    repose::TetMeshingReport tetReport;
    repose::MeshingMask meshing;

    // Body on the meshing grid -> surface -> tets.
    auto meshBody = [&]() {
      t = Clock::now();
      meshing = repose::meshingMask(labels, intensityImage ? &intensity : nullptr, boneOfLabel, skeleton, maskOptions);
      this->MeshingSpacingUsed = meshing.spacing.spacingMm;
      this->NumberOfContactVoxelsCut = static_cast<vtkIdType>(meshing.contacts.voxelsCut);
      this->ContactReport = meshing.contacts.text(skeleton);
      const auto& mg = meshing.mesh.body.grid;
      report << "body mask: " << meshing.bodyVoxels << " voxels";
      if (meshing.closedMm > 0)
      {
        report << " (the labels alone make the body: closed by " << meshing.closedMm << " mm)";
      }
      report << ", " << meshing.components.kept << " piece(s) with bone";
      if (meshing.components.bridged > 0)
      {
        report << ", " << meshing.components.bridged << " without bone bridged to them ("
               << meshing.components.bridgeVoxels << " bridge voxels)";
      }
      if (meshing.components.dropped > 0)
      {
        report << ", " << meshing.components.dropped << " dropped (" << meshing.components.droppedVoxels
               << " voxels: no bone and too small or too far to bridge)";
      }
      report << "; " << meshing.peeledVoxels << " after "
             << (maskOptions.skinLabels.empty() ? "peeling the outer layer"
                                                : "removing " + std::to_string(meshing.skinVoxelsRemoved) +
                                                    " skin voxels")
             << "\nmeshing grid: " << mg.dims[0] << "x" << mg.dims[1] << "x" << mg.dims[2] << " at "
             << meshing.spacing.spacingMm << " mm";
      if (meshing.spacing.trials > 0)
      {
        report << " (chosen for at most " << this->MaxTets << " tets: " << meshing.spacing.surfaceFaces
               << " surface faces, " << meshing.spacing.seeds << " bone seeds, about "
               << std::lround(meshing.spacing.predictedTets) << " tets; " << meshing.spacing.trials << " trials)";
      }
      report << ", " << meshing.meshVoxels << " voxels, " << meshing.contacts.contacts.size()
             << " contact(s) separated, " << meshing.contacts.voxelsCut << " voxels cut (" << SecondsSince(t)
             << " s)\n"
             << this->ContactReport;

      t = Clock::now();
      repose::SeedSteps steps = repose::seedSteps(labels.grid, meshing.spacing.spacingMm);
      if (this->SeedSurfaceStep > 0)
      {
        steps.surface = this->SeedSurfaceStep;
        steps.interior = 2 * steps.surface;
      }
      if (this->SeedInteriorStep > 0)
      {
        steps.interior = this->SeedInteriorStep;
      }
      const repose::Points seeds =
        repose::boneSeedPoints(labels, boneOfLabel, meshing.peeled, steps.surface, steps.interior);
      this->NumberOfSeedPoints = seeds.rows();
      report << "bone seeds: " << seeds.rows() << " (steps " << steps.surface << "/" << steps.interior
             << " voxels, " << SecondsSince(t) << " s)\n";

      vtkSmartPointer<vtkImageData> maskImage = repose_vtk::ToImage(meshing.mesh.body);
      // Surface -> tets; a decimated surface may self-intersect in a narrow gap, then TetGen
      // refuses it and the full-resolution surface is used instead.
      auto meshSurface = [&](double reduction) {
        auto ts = Clock::now();
        vtkNew<vtkPolyData> surface;
        if (!vtkReposeSurfaceExtractor::ContourMask(
              maskImage, 0, this->SurfaceSmoothingIterations, 0.1, reduction, surface))
        {
          throw std::invalid_argument("no body surface could be extracted (MeshingSpacing too coarse for the body?)");
        }
        repose::Points V;
        repose::Triangles F;
        if (!ToTriangles(surface, V, F))
        {
          throw std::invalid_argument("the body surface has non-triangle cells");
        }
        this->NumberOfSurfaceTriangles = F.rows();
        report << "surface: " << V.rows() << " points, " << F.rows() << " triangles (reduction " << reduction
               << ", " << SecondsSince(ts) << " s)\n";
        // TetGen says nothing while it runs: tell the user the size of what it is about to do.
        std::ostringstream progress;
        progress << "TetGen: " << F.rows() << " surface triangles and " << seeds.rows() << " bone seeds";
        if (meshing.spacing.predictedTets > 0)
        {
          progress << " into about " << std::lround(meshing.spacing.predictedTets / 1e3) << " k tets";
        }
        this->SetProgressText(progress.str().c_str());
        this->UpdateProgress(0.3);
        this->SetProgressText(nullptr);  // said once
        return repose::tetrahedralizeSurface(V, F, seeds, meshOptions, &tetReport);
      };
      try
      {
        return meshSurface(this->SurfaceReduction);
      }
      catch (const std::invalid_argument& e)
      {
        if (this->SurfaceReduction <= 0)
        {
          throw;
        }
        report << "decimated surface rejected (" << e.what() << "); meshing the full surface\n";
        return meshSurface(0.0);
      }
    };
    repose::TetMesh mesh = meshBody();
    auto reportTetGen = [&]() {
      report << "tetgen: " << tetReport.nodes << " nodes, " << tetReport.tets << " tets, "
             << (tetReport.surfacePreserved ? "surface kept" : "surface split")
             << (tetReport.preserveFailure.empty() ? "" : " (keeping it failed: " + tetReport.preserveFailure + ")")
             << " (" << tetReport.seconds << " s)\n";
    };
    reportTetGen();
    this->TetGenSeconds = tetReport.seconds;
    // The budget's prediction is a fit: where TetGen exceeds the budget by a tenth, choose again
    // with the tets per surface point this body has shown, and mesh once more.
    if (meshing.spacing.trials > 0 && tetReport.tets > 1.1 * static_cast<double>(this->MaxTets))
    {
      maskOptions.tetsPerPoint =
        1.02 * tetReport.tets / static_cast<double>(meshing.spacing.surfaceFaces + meshing.spacing.seeds);
      report << "over the budget of " << this->MaxTets << " tets (" << maskOptions.tetsPerPoint
             << " tets per surface point): meshing again\n";
      mesh = meshBody();
      reportTetGen();
      this->TetGenSeconds += tetReport.seconds;
    }

    t = Clock::now();
    repose::reorderMeshSpatially(mesh);
    repose::tagMesh(mesh, labels, boneOfLabel);
    const repose::ContactReport contacts = repose::freeBoneContacts(mesh);
    this->NumberOfFreedContactNodes = contacts.nodesFreed;
    if (contacts.bonesKept > 0)
    {
      vtkWarningMacro(<< contacts.bonesKept << " bone(s) touch another bone everywhere in the mesh: "
                      << "their joints cannot bend without inverting tets");
    }
    const repose::ComponentReport components = repose::keepBoneComponents(mesh);
    if (components.componentsDropped > 0)
    {
      vtkWarningMacro("dropped " << components.componentsDropped << " mesh component(s) without bone ("
                                 << components.nodesDropped << " nodes, " << components.tetsDropped
                                 << " tets); kept " << components.componentsKept);
    }
    std::vector<vtkIdType> fixedPerBone(skeleton.size(), 0);
    for (int b : mesh.fixedBone)
    {
      if (b >= 0 && b < int(fixedPerBone.size()))
      {
        ++fixedPerBone[b];
        ++this->NumberOfFixedNodes;
      }
    }
    report << "tagging: " << this->NumberOfFixedNodes << " fixed nodes (" << contacts.nodesFreed
           << " freed where " << contacts.edgesBetweenBones << " edges joined two bones), " << components.componentsKept
           << " component(s) kept, " << components.componentsDropped << " dropped ("
           << components.nodesDropped << " nodes, " << components.tetsDropped << " tets) ("
           << SecondsSince(t) << " s)\n";
    for (std::size_t b = 0; b < fixedPerBone.size(); ++b)
    {
      report << "  " << skeleton.joints[b].name << ": " << fixedPerBone[b] << " fixed nodes\n";
      if (fixedPerBone[b] == 0 && !skeleton.joints[b].labels.empty())
      {
        vtkWarningMacro("bone '" << skeleton.joints[b].name
                                 << "' has no mesh node inside it: its labels are missing from the "
                                    "meshed body or it is thinner than the mesh resolution");
      }
    }

    // Core mesh -> vtkUnstructuredGrid.
    const vtkIdType nv = mesh.nodes.rows(), nt = mesh.tets.rows();
    vtkNew<vtkPoints> points;
    points->SetDataTypeToDouble();
    points->SetNumberOfPoints(nv);
    for (vtkIdType v = 0; v < nv; ++v)
    {
      points->SetPoint(v, mesh.nodes(v, 0), mesh.nodes(v, 1), mesh.nodes(v, 2));
    }
    vtkNew<vtkIdTypeArray> offsets, connectivity;
    offsets->SetNumberOfValues(nt + 1);
    connectivity->SetNumberOfValues(4 * nt);
    for (vtkIdType c = 0; c <= nt; ++c)
    {
      offsets->SetValue(c, 4 * c);
    }
    for (vtkIdType c = 0; c < nt; ++c)
    {
      for (int k = 0; k < 4; ++k)
      {
        connectivity->SetValue(4 * c + k, mesh.tets(c, k));
      }
    }
    vtkNew<vtkCellArray> cells;
    cells->SetData(offsets, connectivity);
    output->SetPoints(points);
    output->SetCells(VTK_TETRA, cells);

    vtkNew<vtkIntArray> fixedBone;
    fixedBone->SetName(repose::arrays::kFixedBone);
    fixedBone->SetNumberOfValues(nv);
    std::copy(mesh.fixedBone.begin(), mesh.fixedBone.end(), fixedBone->GetPointer(0));
    output->GetPointData()->AddArray(fixedBone);
    vtkNew<vtkIntArray> label;
    label->SetName(repose::arrays::kLabel);
    label->SetNumberOfValues(nt);
    std::copy(mesh.tetLabel.begin(), mesh.tetLabel.end(), label->GetPointer(0));
    output->GetCellData()->AddArray(label);

    this->NumberOfNodes = nv;
    this->NumberOfTets = nt;
    this->TotalSeconds = SecondsSince(start);
    report << "output: " << nv << " nodes, " << nt << " tets; total " << this->TotalSeconds << " s\n";
    this->Report = report.str();
  }
  catch (const std::exception& e)
  {
    this->Report = report.str() + "error: " + e.what() + "\n";
    vtkErrorMacro(<< e.what());
    return 0;
  }
  return 1;
}

void vtkReposeBodyMesher::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "SkeletonJSON: " << (this->SkeletonJSON.empty() ? "(empty)" : "(set)") << "\n";
  os << indent << "BodyThreshold: " << this->BodyThreshold << "\n";
  os << indent << "PeelOuterLayer: " << this->PeelOuterLayer << "\n";
  os << indent << "SeparateContacts: " << this->SeparateContacts << "\n";
  os << indent << "SkinLabels:";
  for (int label : this->SkinLabels)
  {
    os << " " << label;
  }
  os << "\n";
  os << indent << "MeshingSpacing: " << this->MeshingSpacing << "\n";
  os << indent << "MaxTets: " << this->MaxTets << "\n";
  os << indent << "MeshingSpacingUsed: " << this->MeshingSpacingUsed << "\n";
  os << indent << "RadiusEdgeRatio: " << this->RadiusEdgeRatio << "\n";
  os << indent << "MaxTetVolume: " << this->MaxTetVolume << "\n";
  os << indent << "SurfaceSmoothingIterations: " << this->SurfaceSmoothingIterations << "\n";
  os << indent << "SeedSurfaceStep: " << this->SeedSurfaceStep << "\n";
  os << indent << "SeedInteriorStep: " << this->SeedInteriorStep << "\n";
  os << indent << "NumberOfNodes: " << this->NumberOfNodes << "\n";
  os << indent << "NumberOfTets: " << this->NumberOfTets << "\n";
}
