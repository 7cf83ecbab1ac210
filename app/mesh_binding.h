#pragma once
// --mesh FILE ...: extra meshes (organs, vessels, a catheter path) bound to a case's rest tet mesh.
#include <memory>
#include <string>

#include "mesh_posing.h"

namespace repose {

class Options;
class Pipeline;

/// The --mesh files bound to the pipeline's rest mesh, the bindings cached in caseDir/bindings;
/// one line per mesh on stdout (vertices, outside the body, bound or read from the cache). Null
/// without --mesh. Throws std::runtime_error for an unknown format and UsageError for two meshes
/// whose outputs would collide.
std::unique_ptr<MeshPoser> bindMeshes(Pipeline& pipeline, const Options& o, const std::string& caseDir);

}  // namespace repose
