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
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataNormals.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>

#include "mesh_io.h"
#include "tet_locator.h"
#include "tet_mesh.h"

namespace repose {
namespace {

using Clock = std::chrono::steady_clock;

Points toPoints(vtkPoints* points) {
  const vtkIdType n = points ? points->GetNumberOfPoints() : 0;
  Points p(n, 3);
  for (vtkIdType i = 0; i < n; ++i) {
    double x[3];
    points->GetPoint(i, x);
    p.row(i) << x[0], x[1], x[2];
  }
  return p;
}

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

}  // namespace

std::string posedMeshName(const std::string& path) {
  return "posed_" + std::filesystem::path(path).filename().string();
}

struct MeshPoser::Rest {
  Points nodes;
  Tets tets;
  std::uint64_t hash = 0;
  std::unique_ptr<TetLocator> locator;  // built on the first binding that is not cached
};

MeshPoser::MeshPoser(vtkUnstructuredGrid* restMesh) : rest_(std::make_unique<Rest>()) {
  if (!restMesh || restMesh->GetNumberOfCells() == 0 || !restMesh->GetPoints())
    throw std::runtime_error("mesh posing: the case has no tet mesh");
  rest_->nodes = toPoints(restMesh->GetPoints());
  const vtkIdType nc = restMesh->GetNumberOfCells();
  rest_->tets.resize(nc, 4);
  vtkCellArray* cells = restMesh->GetCells();
  vtkDataArray* conn = cells->GetConnectivityArray();
  vtkDataArray* offsets = cells->GetOffsetsArray();
  vtkUnsignedCharArray* types = restMesh->GetCellTypesArray();
  if (conn->GetNumberOfTuples() != 4 * nc)
    throw std::runtime_error("mesh posing: the case's mesh has cells that are not tetrahedra");
  for (vtkIdType c = 0; c < nc; ++c) {
    if ((types && types->GetValue(c) != VTK_TETRA) || vtkIdType(offsets->GetTuple1(c)) != 4 * c)
      throw std::runtime_error("mesh posing: the case's mesh has cells that are not tetrahedra");
    for (int k = 0; k < 4; ++k) rest_->tets(c, k) = int(conn->GetTuple1(4 * c + k));
  }
  rest_->hash = contentHash(rest_->tets.data(), std::size_t(rest_->tets.size()) * sizeof(int),
                            contentHash(rest_->nodes.data(), std::size_t(rest_->nodes.size()) * sizeof(double)));
}

MeshPoser::~MeshPoser() = default;

const PoseableMesh& MeshPoser::add(const std::string& path, const std::string& cacheDir) {
  PoseableMesh m;
  m.path = path;
  m.rest = readPolyData(path);
  const auto t0 = Clock::now();
  const Points points = toPoints(m.rest->GetPoints());
  const std::uint64_t pointsHash = contentHash(points.data(), std::size_t(points.size()) * sizeof(double));
  const std::size_t nodeCount = std::size_t(rest_->nodes.rows()), tetCount = std::size_t(rest_->tets.rows());
  Binding binding;
  if (!cacheDir.empty()) {
    m.cachePath = cacheDir + "/" + safeStem(path) + "-" + hex16(pointsHash) + ".bin";
    m.fromCache = readBindingCache(m.cachePath, pointsHash, rest_->hash, std::size_t(points.rows()), nodeCount,
                                   tetCount, binding);
  }
  if (!m.fromCache) {
    try {
      if (!rest_->locator) rest_->locator = std::make_unique<TetLocator>(rest_->nodes, rest_->tets);
      binding = bindPoints(*rest_->locator, points);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(path + ": cannot bind to the case's mesh (" + e.what() + ")");
    }
    if (!cacheDir.empty()) {
      try {
        std::error_code ec;
        std::filesystem::create_directories(cacheDir, ec);
        if (ec) throw std::runtime_error(cacheDir + ": cannot create (" + ec.message() + ")");
        writeBindingCache(m.cachePath, binding, pointsHash, rest_->hash, nodeCount, tetCount);
      } catch (const std::exception& e) {
        m.cacheWarning = e.what();
        m.cachePath.clear();
      }
    }
  }
  m.outside = binding.outsideCount;
  try {
    m.binding = makeNodeBinding(binding, rest_->tets);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  m.bindSeconds = std::chrono::duration<double>(Clock::now() - t0).count();
  meshes_.push_back(std::move(m));
  return meshes_.back();
}

vtkSmartPointer<vtkPolyData> MeshPoser::pose(std::size_t i, vtkUnstructuredGrid* posedMesh) const {
  if (i >= meshes_.size()) throw std::out_of_range("mesh posing: no mesh " + std::to_string(i));
  const PoseableMesh& m = meshes_[i];
  vtkPoints* nodes = posedMesh ? posedMesh->GetPoints() : nullptr;
  if (!nodes || std::size_t(nodes->GetNumberOfPoints()) != std::size_t(rest_->nodes.rows()))
    throw std::runtime_error("mesh posing: the posed tet mesh does not match the case's rest mesh");
  const vtkIdType n = m.rest->GetNumberOfPoints();
  auto moved = vtkSmartPointer<vtkPoints>::New();
  moved->SetDataTypeToFloat();
  moved->SetNumberOfPoints(n);
  float* dst = vtkFloatArray::SafeDownCast(moved->GetData())->GetPointer(0);
  vtkDataArray* data = nodes->GetData();
  const std::size_t nv = std::size_t(nodes->GetNumberOfPoints());
  try {
    if (auto* f = vtkArrayDownCast<vtkAOSDataArrayTemplate<float>>(data)) {
      applyBinding(m.binding, f->GetPointer(0), nv, dst);
    } else if (auto* d = vtkArrayDownCast<vtkAOSDataArrayTemplate<double>>(data)) {
      applyBinding(m.binding, d->GetPointer(0), nv, dst);
    } else {
      const Points p = toPoints(nodes);
      applyBinding(m.binding, p.data(), nv, dst);
    }
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(m.path + ": " + e.what());
  }
  auto out = vtkSmartPointer<vtkPolyData>::New();
  out->ShallowCopy(m.rest);
  out->SetPoints(moved);
  // Rest normals are wrong after deformation: recompute them (same points and cells) where there were any.
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
