#include "mesh_posing.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <unistd.h>

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDataArray.h>
#include <vtkFloatArray.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataNormals.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>

#include "ReposeMeshConversion.h"
#include "array_names.h"
#include "mesh_io.h"
#include "repose_pipeline.h"
#include "tet_mesh.h"
#include "vtkReposeSurfaceBinding.h"
#include "vtkReposeSurfaceDeformer.h"

namespace repose {
namespace {

using Clock = std::chrono::steady_clock;

std::string hex16(std::uint64_t h) {
  std::ostringstream s;
  s << std::hex << std::setw(16) << std::setfill('0') << h;
  return s.str();
}

std::string safeStem(const std::string& path) {
  std::string stem = std::filesystem::path(path).stem().string();
  for (char& c : stem)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';
  return stem.empty() ? "mesh" : stem;
}

// The binding as the filters carry it: point data BoundTet and BoundWeights on a copy of `rest`.
vtkSmartPointer<vtkPolyData> withBinding(vtkPolyData* rest, const Binding& binding) {
  const vtkIdType n = vtkIdType(binding.tet.size());
  auto tets = vtkSmartPointer<vtkIntArray>::New();
  tets->SetName(arrays::kBoundTet);
  tets->SetNumberOfTuples(n);
  std::copy(binding.tet.begin(), binding.tet.end(), tets->GetPointer(0));
  auto weights = vtkSmartPointer<vtkFloatArray>::New();
  weights->SetName(arrays::kBoundWeights);
  weights->SetNumberOfComponents(4);
  weights->SetNumberOfTuples(n);
  std::copy(binding.bary.data(), binding.bary.data() + 4 * n, weights->GetPointer(0));
  auto bound = vtkSmartPointer<vtkPolyData>::New();
  bound->ShallowCopy(rest);
  bound->GetPointData()->AddArray(tets);
  bound->GetPointData()->AddArray(weights);
  return bound;
}

// The binding back from the filter's arrays (for the cache file).
Binding bindingOf(vtkPolyData* bound, std::size_t outside) {
  auto* tets = vtkIntArray::SafeDownCast(bound->GetPointData()->GetArray(arrays::kBoundTet));
  auto* weights = vtkFloatArray::SafeDownCast(bound->GetPointData()->GetArray(arrays::kBoundWeights));
  if (!tets || !weights) throw std::logic_error("mesh posing: the binding filter left no BoundTet/BoundWeights");
  const vtkIdType n = tets->GetNumberOfTuples();
  Binding b;
  b.tet.assign(tets->GetPointer(0), tets->GetPointer(0) + n);
  b.bary.resize(n, 4);
  std::copy(weights->GetPointer(0), weights->GetPointer(0) + 4 * n, b.bary.data());
  b.outsideCount = outside;
  return b;
}

}  // namespace

std::string posedMeshName(const std::string& path) {
  return "posed_" + std::filesystem::path(path).filename().string();
}

// The rest mesh's fingerprint keys the binding cache; the filters do the binding and the posing.
struct MeshPoser::Rest {
  vtkSmartPointer<vtkUnstructuredGrid> mesh;
  std::size_t nodes = 0, tets = 0;
  std::uint64_t hash = 0;
  vtkNew<vtkReposeSurfaceBinding> binder;  // keeps its locator between meshes
  std::vector<vtkSmartPointer<vtkReposeSurfaceDeformer>> deformers;  // one per mesh: keeps its binding
};

MeshPoser::MeshPoser(vtkUnstructuredGrid* restMesh) : rest_(std::make_unique<Rest>()) {
  if (!restMesh || restMesh->GetNumberOfCells() == 0 || !restMesh->GetPoints())
    throw std::runtime_error("mesh posing: the case has no tet mesh");
  Points nodes;
  Tets tets;
  try {
    nodes = repose_vtk::ToPoints(restMesh->GetPoints());
    tets = repose_vtk::ToTets(restMesh, "the case's mesh");
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(std::string("mesh posing: ") + e.what());
  }
  rest_->mesh = restMesh;
  rest_->nodes = std::size_t(nodes.rows());
  rest_->tets = std::size_t(tets.rows());
  rest_->hash = contentHash(tets.data(), std::size_t(tets.size()) * sizeof(int),
                            contentHash(nodes.data(), std::size_t(nodes.size()) * sizeof(double)));
  rest_->binder->SetTetMeshData(restMesh);
}

MeshPoser::~MeshPoser() = default;

const PoseableMesh& MeshPoser::add(const std::string& path, const std::string& cacheDir) {
  PoseableMesh m;
  m.path = path;
  m.rest = readPolyData(path);
  const auto t0 = Clock::now();
  const Points points = repose_vtk::ToPoints(m.rest->GetPoints());
  const std::uint64_t pointsHash = contentHash(points.data(), std::size_t(points.size()) * sizeof(double));
  Binding cached;
  if (!cacheDir.empty()) {
    m.cachePath = cacheDir + "/" + safeStem(path) + "-" + hex16(pointsHash) + ".bin";
    m.fromCache = readBindingCache(m.cachePath, pointsHash, rest_->hash, std::size_t(points.rows()), rest_->nodes,
                                   rest_->tets, cached);
  }
  if (m.fromCache) {
    m.bound = withBinding(m.rest, cached);
    m.outside = cached.outsideCount;
  } else {
    rest_->binder->SetInputData(m.rest);
    updateOrThrowFor(rest_->binder, path, "cannot bind to the case's mesh");
    m.bound = vtkSmartPointer<vtkPolyData>::New();
    m.bound->ShallowCopy(rest_->binder->GetOutput());
    rest_->binder->SetInputData(nullptr);
    m.outside = std::size_t(rest_->binder->GetOutsideCount());
    if (!cacheDir.empty()) {
      try {
        std::error_code ec;
        std::filesystem::create_directories(cacheDir, ec);
        if (ec) throw std::runtime_error(cacheDir + ": cannot create (" + ec.message() + ")");
        writeBindingCache(m.cachePath, bindingOf(m.bound, m.outside), pointsHash, rest_->hash, rest_->nodes,
                          rest_->tets);
      } catch (const std::exception& e) {
        m.cacheWarning = e.what();
        m.cachePath.clear();
      }
    }
  }
  auto deformer = vtkSmartPointer<vtkReposeSurfaceDeformer>::New();
  deformer->SetInputData(m.bound);
  rest_->deformers.push_back(deformer);
  m.bindSeconds = std::chrono::duration<double>(Clock::now() - t0).count();
  meshes_.push_back(std::move(m));
  return meshes_.back();
}

vtkSmartPointer<vtkPolyData> MeshPoser::pose(std::size_t i, vtkUnstructuredGrid* posedMesh) const {
  if (i >= meshes_.size()) throw std::out_of_range("mesh posing: no mesh " + std::to_string(i));
  const PoseableMesh& m = meshes_[i];
  vtkPoints* nodes = posedMesh ? posedMesh->GetPoints() : nullptr;
  if (!nodes || std::size_t(nodes->GetNumberOfPoints()) != rest_->nodes)
    throw std::runtime_error("mesh posing: the posed tet mesh does not match the case's rest mesh");
  vtkReposeSurfaceDeformer* deformer = rest_->deformers[i];
  deformer->SetPosedMeshData(posedMesh);
  updateOrThrowFor(deformer, m.path, "cannot pose");
  // The deformer reuses its points between poses: this pose keeps its own. The binding arrays stay behind.
  auto moved = vtkSmartPointer<vtkPoints>::New();
  moved->DeepCopy(deformer->GetOutput()->GetPoints());
  auto out = vtkSmartPointer<vtkPolyData>::New();
  out->ShallowCopy(m.rest);
  out->SetPoints(moved);
  // Rest normals are wrong after deformation: recompute them (same points and cells) where there were any.
  const vtkIdType n = m.rest->GetNumberOfPoints();
  const bool hadNormals = m.rest->GetPointData()->GetNormals() != nullptr;
  out->GetPointData()->SetNormals(nullptr);
  out->GetCellData()->SetNormals(nullptr);
  if (hadNormals && out->GetNumberOfPolys() > 0 && out->GetNumberOfStrips() == 0) {
    auto normals = vtkSmartPointer<vtkPolyDataNormals>::New();
    normals->SetInputData(out);
    normals->SplittingOff();
    normals->ConsistencyOff();
    normals->ComputeCellNormalsOff();
    normals->Update();
    auto withNormals = vtkSmartPointer<vtkPolyData>::New();
    withNormals->ShallowCopy(normals->GetOutput());
    if (withNormals->GetNumberOfPoints() == n && withNormals->GetNumberOfCells() == out->GetNumberOfCells())
      out = withNormals;
  }
  return out;
}

}  // namespace repose
