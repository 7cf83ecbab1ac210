#include "mesh_binding.h"

#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <set>
#include <stdexcept>
#include <vector>

#include <vtkPolyData.h>

#include "cli_options.h"
#include "mesh_io.h"
#include "repose_pipeline.h"

namespace repose {

std::unique_ptr<MeshPoser> bindMeshes(Pipeline& pipeline, const Options& o, const std::string& caseDir) {
  const std::vector<std::string> paths = o.all("mesh");
  if (paths.empty()) return nullptr;
  std::set<std::string> names;
  for (const auto& path : paths) {
    if (!isSurfaceMeshPath(path))
      throw std::runtime_error(path + ": unknown mesh format (expected .obj, .stl, .ply, .vtp or .vtk)");
    // Stems, not names: animate writes every mesh's frames as <stem>_NNNNN.vtp.
    const std::string stem = std::filesystem::path(path).stem().string();
    // pose writes posed_<name>, animate frames/<stem>_NNNNN.vtp: these stems are Repose's own outputs.
    for (const char* own : {"surfaces", "mesh", "labels", "image", "displacement"})
      if (stem == own)
        throw UsageError("--mesh " + path + ": a mesh named '" + stem + "' would be written over Repose's own posed " +
                         own + " (posed_" + own + ".*, frames/" + own + "_NNNNN.*); give the file another name");
    if (!names.insert(stem).second)
      throw UsageError("two --mesh files are named " + std::filesystem::path(path).filename().string() +
                       " (their outputs would collide)");
  }
  auto poser = std::make_unique<MeshPoser>(pipeline.restMesh());
  for (const auto& path : paths) {
    const PoseableMesh& m = poser->add(path, caseDir + "/bindings");
    const vtkIdType n = m.rest->GetNumberOfPoints();
    std::cout << "mesh " << path << ": " << n << " vertices, " << m.outside << " outside the body ("
              << std::fixed << std::setprecision(1) << 100.0 * double(m.outside) / double(std::max<vtkIdType>(n, 1))
              << " %), " << (m.fromCache ? "binding read from the cache" : "bound") << " in " << std::setprecision(3)
              << m.bindSeconds << " s\n";
    std::cout.unsetf(std::ios::floatfield);
    if (!m.cacheWarning.empty()) std::cerr << "repose: warning: binding not cached: " << m.cacheWarning << "\n";
  }
  return poser;
}

}  // namespace repose
