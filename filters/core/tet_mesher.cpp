// The only file that includes tetgen.h (TetGen is AGPL; keep it swappable).
#include "tet_mesher.h"

#include <tetgen.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <new>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace repose {

namespace {

std::string tetgenErrorText(int code) {
  switch (code) {
    case 1: return "out of memory (reduce the surface size or the meshing resolution)";
    case 2: return "internal error of TetGen";
    case 3: return "the surface intersects itself (smooth less or check the mask for thin, touching parts)";
    case 4: return "the surface has a very small feature compared to its size (check for degenerate triangles)";
    case 5: return "two surface facets are very close to each other (parts of the surface almost touch)";
    case 10: return "TetGen rejected the input";
    default: return "TetGen failed with code " + std::to_string(code);
  }
}

// A closed 2-manifold: every undirected edge is used by exactly two triangles.
void checkClosedSurface(const Triangles& F) {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(std::size_t(F.rows()) * 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int c = 0; c < 3; ++c) {
      int a = F(f, c), b = F(f, (c + 1) % 3);
      if (a == b) throw std::invalid_argument("tet mesher: triangle " + std::to_string(f) + " is degenerate");
      edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  std::sort(edges.begin(), edges.end());
  std::size_t open = 0, nonManifold = 0;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i == 1) ++open;
    else if (j - i > 2) ++nonManifold;
    i = j;
  }
  if (open || nonManifold)
    throw std::invalid_argument("tet mesher: the surface is not a closed manifold (" + std::to_string(open) +
                                " open edges, " + std::to_string(nonManifold) +
                                " edges shared by more than two triangles)");
}

// The facet -> vertices map TetGen's refinement reads (idx2facetlist, facetverticeslist), made as
// tetgenmesh::makefacetverticesmap() makes it (same facet indices, same vertices in the same order)
// but into one flat array. TetGen's own keeps every facet's vertices in an arraypool of its own
// until all are found: 3 KiB per facet, and each surface triangle is a facet, so 0.4 GB at once on
// a 128 k-triangle body surface, 0.85 GB on 291 k: the peak of the whole preprocessing.
void buildFacetVerticesMap(tetgenmesh& m) {
  using Point = tetgenmesh::point;
  std::vector<int> firstVertex{0};
  std::vector<Point> vertices;
  auto addVertex = [&](Point p) {
    const auto type = m.pointtype(p);
    if (type == tetgenmesh::FREESEGVERTEX || type == tetgenmesh::FREEFACETVERTEX) return;
    m.pinfect(p);
    vertices.push_back(p);
  };
  tetgenmesh::face subface, neighbour, *member, *added;
  m.subfaces->traversalinit();
  for (subface.sh = m.shellfacetraverse(m.subfaces); subface.sh; subface.sh = m.shellfacetraverse(m.subfaces)) {
    if (m.sinfected(subface)) continue;  // its facet is done
    // A new facet: flood its subfaces across the edges that are not segments.
    const auto corners = reinterpret_cast<Point*>(&subface.sh[3]);
    for (int k = 0; k < 3; ++k) addVertex(corners[k]);
    m.sinfect(subface);
    m.caveshlist->newindex(reinterpret_cast<void**>(&member));
    *member = subface;
    for (long i = 0; i < m.caveshlist->objects; ++i) {
      member = static_cast<tetgenmesh::face*>(fastlookup(m.caveshlist, i));
      m.setfacetindex(*member, int(firstVertex.size()) - 1);
      for (int j = 0; j < 3; ++j, m.senextself(*member)) {
        if (isshsubseg(*member)) continue;
        m.spivot(*member, neighbour);
        if (m.sinfected(neighbour)) continue;
        if (!m.pinfected(m.sapex(neighbour))) addVertex(m.sapex(neighbour));
        m.sinfect(neighbour);
        m.caveshlist->newindex(reinterpret_cast<void**>(&added));
        *added = neighbour;
      }
    }
    for (auto v = vertices.begin() + firstVertex.back(); v != vertices.end(); ++v) m.puninfect(*v);
    m.caveshlist->restart();
    firstVertex.push_back(int(vertices.size()));
  }
  m.subfaces->traversalinit();
  for (subface.sh = m.shellfacetraverse(m.subfaces); subface.sh; subface.sh = m.shellfacetraverse(m.subfaces))
    m.suninfect(subface);
  m.idx2facetlist = new int[firstVertex.size()];
  std::copy(firstVertex.begin(), firstVertex.end(), m.idx2facetlist);
  m.facetverticeslist = new Point[vertices.size()];
  std::copy(vertices.begin(), vertices.end(), m.facetverticeslist);
  m.totalworkmemory += firstVertex.size() * sizeof(int) + vertices.size() * sizeof(Point);
}

// Queues every item of `items` into a new pool of bad ones and repairs them (chkencflag as TetGen's).
void repairAll(tetgenmesh& m, tetgenmesh::memorypool* items, tetgenmesh::memorypool*& bad, int chkencflag) {
  bad = new tetgenmesh::memorypool(sizeof(tetgenmesh::face), m.b->shellfaceperblock, sizeof(void*), 0);
  tetgenmesh::face item;
  items->traversalinit();
  for (item.sh = m.shellfacetraverse(items); item.sh; item.sh = m.shellfacetraverse(items)) m.enqueuesubface(bad, &item);
  if (chkencflag == 1) m.repairencsegs(chkencflag);
  else m.repairencfacs(chkencflag);
}

// tetgenmesh::delaunayrefinement() with the facet map of buildFacetVerticesMap: encroached segments
// and subfaces (without -Y), then bad tets, in TetGen's order, so the mesh is the same to the bit.
// Without -S (not used here) there is no limit on the Steiner points to check first.
void refineMesh(tetgenmesh& m) {
  tetgenbehavior& b = *m.b;
  if (m.useinsertradius) {
    if ((b.plc && b.nobisect) || b.refine) m.makesegmentendpointsmap();
    buildFacetVerticesMap(m);
  }
  m.steinerleft = b.steinerleft;
  m.encseglist = new tetgenmesh::arraypool(sizeof(tetgenmesh::face), 8);
  m.encshlist = new tetgenmesh::arraypool(sizeof(tetgenmesh::badface), 8);
  const bool splitBoundary = !b.nobisect || m.checkconstraints;
  if (splitBoundary) {
    repairAll(m, m.subsegs, m.badsubsegs, 1);
    if (b.reflevel > 1) repairAll(m, m.subfaces, m.badsubfacs, 2);
  }
  if (b.reflevel > 2) {
    m.cosmindihed = std::cos(b.mindihedral / 180.0 * tetgenmesh::PI);
    m.badtetrahedrons = new tetgenmesh::memorypool(sizeof(tetgenmesh::triface), b.tetrahedraperblock, sizeof(void*), 0);
    tetgenmesh::triface tet;
    m.tetrahedrons->traversalinit();
    for (tet.tet = m.tetrahedrontraverse(); tet.tet; tet.tet = m.tetrahedrontraverse()) m.enqueuetetrahedron(&tet);
    m.repairbadtets(4);
  }
  delete m.encseglist;
  delete m.encshlist;
  m.encseglist = m.encshlist = nullptr;
  if (splitBoundary) {
    delete m.badsubsegs;
    if (b.reflevel > 1) delete m.badsubfacs;
  }
  if (b.reflevel > 2) delete m.badtetrahedrons;
  m.badsubsegs = m.badsubfacs = m.badtetrahedrons = nullptr;
}

// TetGen 1.5.0's tetrahedralize() crashes when it reports an error: terminatetetgen() frees the mesh
// and throws, then the destructor of its stack mesh frees it again. So the stages we use (-p, -q, -Y;
// no -r/-m/-R) are driven here with a heap mesh, leaked on error (its pools are already freed then).
// With -Y, tetrahedralize() would next remove the few Steiner points the constrained Delaunay stage
// put on the surface (suppresssteinerpoints(), which crashes in 1.5.0 on body surfaces) and restore
// the Delaunay property around them; both are skipped: those points stay, the surface is unchanged.
// Seeds are passed as isolated input points, not with -i: 1.5.0's insertconstrainedpoints() can walk
// off the carved mesh and crash.
// With -Y, tetrahedralize() recovers the boundary without splitting segments, so initializepools()
// leaves useinsertradius off and a split segment would not inherit its segment index; the constrained
// Delaunay stage run here does split segments and then reads that index (uninitialised: wrong Steiner
// points or a crash). Setting it first gives the pools the layout and bookkeeping of the -p path.
// The refinement is driven here too (refineMesh): see buildFacetVerticesMap.
void runTetGen(tetgenbehavior& b, tetgenio& in, tetgenio& out) {
  auto* m = new tetgenmesh();
  try {
    m->b = &b;
    m->in = &in;
    m->useinsertradius = 1;
    m->initializepools();
    m->transfernodes();
    exactinit(b.verbose, b.noexact, b.nostaticfilter, m->xmax - m->xmin, m->ymax - m->ymin, m->zmax - m->zmin);
    clock_t stamp;
    m->incrementaldelaunay(stamp);
    m->meshsurface();
    m->constraineddelaunay(stamp);
    m->carveholes();
    if (b.quality) refineMesh(*m);
    if (b.optlevel > 0) m->optimizemesh();
    if (!b.nojettison && (m->dupverts > 0 || m->unuverts > 0)) m->jettisonnodes();
    out.firstnumber = in.firstnumber;
    out.mesh_dim = in.mesh_dim;
    m->outnodes(&out);
    if (m->tetrahedrons->items > 0) m->outelements(&out);
  } catch (int) {
    throw;  // m is leaked on purpose, see above
  }
  delete m;
}

}  // namespace

TetMesh tetrahedralizeSurface(const Points& V, const Triangles& F, const Points& seeds,
                              const TetMeshingOptions& options, TetMeshingReport* report) {
  const auto start = std::chrono::steady_clock::now();
  if (V.rows() < 4 || F.rows() < 4)
    throw std::invalid_argument("tet mesher: the surface needs at least 4 points and 4 triangles (got " +
                                std::to_string(V.rows()) + " and " + std::to_string(F.rows()) + ")");
  if (!V.allFinite()) throw std::invalid_argument("tet mesher: surface points must be finite");
  if (seeds.rows() > 0 && !seeds.allFinite()) throw std::invalid_argument("tet mesher: seed points must be finite");
  if (F.minCoeff() < 0 || F.maxCoeff() >= V.rows())
    throw std::invalid_argument("tet mesher: a triangle refers to a point index outside [0, " +
                                std::to_string(V.rows()) + ")");
  if (options.radiusEdgeRatio != 0 && !(options.radiusEdgeRatio > 1.0))
    throw std::invalid_argument("tet mesher: the radius-edge ratio must be > 1 (e.g. 1.6), or 0 for no quality bound");
  if (options.minDihedralDegrees < 0 || options.minDihedralDegrees >= 70)
    throw std::invalid_argument("tet mesher: the minimum dihedral angle must be in [0, 70) degrees");
  if (options.maxTetVolume < 0) throw std::invalid_argument("tet mesher: the maximum tet volume must be >= 0");
  checkClosedSurface(F);

  // Seeds outside the surface's bounding box are dropped here: TetGen would discard them anyway,
  // but a far point enlarges its working box and then its volume bound (-a) is not enforced.
  const Eigen::RowVector3d lo = V.colwise().minCoeff(), hi = V.colwise().maxCoeff();
  std::vector<Eigen::Index> keptSeeds;
  for (Eigen::Index s = 0; s < seeds.rows(); ++s)
    if ((seeds.row(s).array() >= lo.array()).all() && (seeds.row(s).array() <= hi.array()).all())
      keptSeeds.push_back(s);

  tetgenio in;
  in.firstnumber = 0;
  // Surface points, then the seeds as isolated points (TetGen drops those outside the surface).
  in.numberofpoints = int(V.rows() + Eigen::Index(keptSeeds.size()));
  in.pointlist = new REAL[std::size_t(in.numberofpoints) * 3];
  std::copy(V.data(), V.data() + V.size(), in.pointlist);  // row-major #V by 3
  for (std::size_t s = 0; s < keptSeeds.size(); ++s)
    for (int c = 0; c < 3; ++c) in.pointlist[V.size() + 3 * s + c] = seeds(keptSeeds[s], c);
  in.numberoffacets = int(F.rows());
  in.facetlist = new tetgenio::facet[std::size_t(F.rows())];
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    tetgenio::facet& facet = in.facetlist[f];
    tetgenio::init(&facet);
    facet.numberofpolygons = 1;
    facet.polygonlist = new tetgenio::polygon[1];
    tetgenio::init(&facet.polygonlist[0]);
    facet.polygonlist[0].numberofvertices = 3;
    facet.polygonlist[0].vertexlist = new int[3]{F(f, 0), F(f, 1), F(f, 2)};
  }

  // p: PLC, q: quality bound, a: volume bound, Y: surface preserved, z: zero-based, F: no face
  // output (not needed), Q/V: quiet/verbose.
  auto switchesFor = [&](bool preserve) {
    std::ostringstream sw;
    sw.precision(17);
    sw << "p";
    if (options.radiusEdgeRatio > 0) {
      sw << "q" << options.radiusEdgeRatio;
      if (options.minDihedralDegrees > 0) sw << "/" << options.minDihedralDegrees;
    }
    if (options.maxTetVolume > 0) sw << "a" << options.maxTetVolume;
    if (preserve) sw << "Y";
    sw << "zF" << (options.verbose ? "V" : "Q");
    return sw.str();
  };
  auto runWith = [&](bool preserve, tetgenio& result) {
    std::string switches = switchesFor(preserve);
    tetgenbehavior behavior;
    if (!behavior.parse_commandline(&switches[0]))
      throw std::invalid_argument("tet mesher: TetGen rejected the switches '" + switches + "'");
    try {
      runTetGen(behavior, in, result);
    } catch (int code) {
      throw std::invalid_argument("tet mesher: " + tetgenErrorText(code));
    } catch (const std::bad_alloc&) {
      throw std::invalid_argument("tet mesher: " + tetgenErrorText(1));
    }
    if (result.numberoftetrahedra <= 0 || result.numberofcorners < 4)
      throw std::invalid_argument("tet mesher: TetGen produced no tetrahedra (is the surface closed and non-degenerate?)");
  };
  tetgenio preserved;
  tetgenio split;
  bool surfacePreserved = false;
  std::string preserveFailure;
  if (options.preserveSurface && options.maxTetVolume <= 0) {
    try {
      runWith(true, preserved);
      surfacePreserved = true;
    } catch (const std::invalid_argument& e) {
      preserveFailure = e.what();
    }
  }
  if (!surfacePreserved) runWith(false, split);
  tetgenio& out = surfacePreserved ? preserved : split;

  // Keep only nodes used by tets, renumbered in their original order.
  const int nOut = out.numberofpoints;
  const int nc = out.numberofcorners;
  std::vector<int> newIndex(std::size_t(nOut), -1);
  for (int t = 0; t < out.numberoftetrahedra; ++t)
    for (int c = 0; c < 4; ++c) {
      const int v = out.tetrahedronlist[std::size_t(t) * nc + c];
      if (v < 0 || v >= nOut) throw std::invalid_argument("tet mesher: TetGen returned an invalid node index");
      newIndex[v] = 0;
    }
  int used = 0;
  for (auto& v : newIndex)
    if (v == 0) v = used++;

  TetMesh mesh;
  mesh.nodes.resize(used, 3);
  for (int v = 0; v < nOut; ++v)
    if (newIndex[v] >= 0)
      for (int c = 0; c < 3; ++c) mesh.nodes(newIndex[v], c) = out.pointlist[std::size_t(v) * 3 + c];
  mesh.tets.resize(out.numberoftetrahedra, 4);
  for (int t = 0; t < out.numberoftetrahedra; ++t) {
    for (int c = 0; c < 4; ++c) mesh.tets(t, c) = newIndex[out.tetrahedronlist[std::size_t(t) * nc + c]];
    const Eigen::Vector3d a = mesh.nodes.row(mesh.tets(t, 0)), b = mesh.nodes.row(mesh.tets(t, 1)),
                          c = mesh.nodes.row(mesh.tets(t, 2)), d = mesh.nodes.row(mesh.tets(t, 3));
    if (tetVolume(a, b, c, d) < 0) std::swap(mesh.tets(t, 2), mesh.tets(t, 3));
  }

  if (report) {
    report->inputPoints = int(V.rows());
    report->inputFacets = int(F.rows());
    report->seedPoints = int(seeds.rows());
    report->nodes = int(mesh.nodes.rows());
    report->tets = int(mesh.tets.rows());
    report->surfacePreserved = surfacePreserved;
    report->preserveFailure = preserveFailure;
    report->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return mesh;
}

}  // namespace repose
