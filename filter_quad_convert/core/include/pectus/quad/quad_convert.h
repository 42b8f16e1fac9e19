// Triangle-to-quad conversion (thesis 4.1.2): adjacent triangle pairs merged into quads, chosen greedily
// by the quad's shape quality beta (the thesis' conversion scheme) or by a maximum-weight matching of the
// dual graph (as gmsh's Blossom-Quad). Leftover triangles either stay (quad-dominant) or the whole mesh
// is split once Catmull-Clark style (quad -> 4 quads, triangle -> 3 quads; all quads), the new nodes on
// the C1 surface of the input (thesis chapter 3).
#pragma once
#include <functional>

#include "pectus/c1/surface.h"
#include "pectus/quad/poly_mesh.h"

namespace pectus::quad {

enum class Pairing { Greedy, Optimal };
enum class Leftovers { QuadDominant, AllQuads };

struct ConvertOptions {
  Pairing pairing = Pairing::Optimal;
  Leftovers leftovers = Leftovers::AllQuads;
  /// a pair is merged only if its quad's beta is above this (never below 0: no non-convex or inverted quad)
  double minQuality = 0.0;
  /// a pair is merged only if the angle between its two triangles' normals is at most this (degrees)
  double maxDihedralDeg = 60.0;
};

struct ConvertResult {
  PolyMesh mesh;
  std::size_t candidates = 0;          ///< triangle pairs that make an acceptable quad
  std::size_t merged = 0;              ///< pairs merged
  std::size_t leftoverTriangles = 0;   ///< triangles left unpaired by the matching
  bool subdivided = false;             ///< AllQuads with leftovers: the mesh was split once
  std::size_t newNodes = 0;            ///< nodes added by the split (on the C1 surface)
  double totalBeta = 0;                ///< sum of beta over the merged pairs
  PolyStats stats;
  double seconds = 0;
};

/// Dual-graph candidates of a triangle mesh: a pair of edge-adjacent, consistently oriented triangles whose
/// quad (a, d, b, c) (shared edge a-b) has beta > minQuality both along its own normal and along the mean
/// normal of the two triangles. w = beta.
struct Candidate {
  int t0, t1;
  std::array<int, 4> quad;
  double beta;
};
std::vector<Candidate> quadCandidates(const c1::TriMesh& tri, const ConvertOptions& o);

/// Throws TopologyError for input that cannot be converted (no triangle, no pair at all), and what
/// requireFiniteVertices (InputError) / requireElementIndices (TopologyError) throw.
ConvertResult convertToQuads(const c1::TriMesh& tri, const ConvertOptions& o);

/// One Catmull-Clark style split of a triangle/quad mesh: every element with n sides -> n quads, new nodes at
/// edge midpoints and element centres, placed by `place(linearPosition)` (e.g. the closest point of
/// a surface). Edge midpoints are shared; the old vertices keep their indices.
using PlaceFn = std::function<Vec3(const Vec3& linear)>;
PolyMesh splitToQuads(const PolyMesh& m, const PlaceFn& place, std::size_t* newNodes = nullptr);

}  // namespace pectus::quad
