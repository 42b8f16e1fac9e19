// Tetrahedralisation of a closed, labelled triangle surface with TetGen 1.5 (Debian libtet1.5-dev).
#pragma once
#include <array>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "pectus/fe/tet_mesh.h"
#include "pectus/surface.h"

namespace pectus::fe {

/// The surface to mesh (V in mm; F oriented or not, forming closed 2-manifold shells) with a tissue per face
struct SurfaceMesh : pectus::Surface {
  std::vector<int> faceTissue;  ///< per face tissue label (pectus::Tissue)
};

struct TetgenOptions {
  double radiusEdgeRatio = 1.6;  ///< TetGen -q: max radius-edge ratio (quality); <= 0: no quality refinement
  double maxVolume = 0;          ///< TetGen -a: max tet volume in mm^3; <= 0: no limit
  int order = 1;                 ///< 1: TET4, 2: TET10 (straight mid-edge nodes added by toQuadratic)
  bool preserveSurface = false;  ///< TetGen -Y: no Steiner points on the surface
  /// TetGen -S: at most this many points added to the input's (quality and volume refinement stop there,
  /// leaving tets above the bounds; a surface whose recovery needs more is a pectus::TopologyError); < 0: no limit.
  /// Bounds the mesh's size, and so time and memory, whatever the surface's features.
  int maxAddedPoints = -1;
  /// TetGen runs in a child process; one still running after this many seconds is stopped (its quality
  /// refinement can go on without end on tiny features) and the call throws TopologyError; <= 0: no limit
  double timeLimitSeconds = 900;
};

/// The first pair of faces (a < b) of the surface that intersect each other (touching through a shared
/// vertex or edge is not an intersection; a == b: a degenerate face with collinear corners), by the
/// project's one exact check (pectus/self_intersections.h, CGAL); nullopt if none. The surface must be
/// closed (as checkSurfaceForTetgen checks first).
std::optional<std::pair<int, int>> findSelfIntersection(const SurfaceMesh& s);

/// Checks the surface is closed (every edge in exactly two faces), has valid indices, one label per
/// face and no self-intersection; throws pectus::TopologyError naming the faulty edge or face pair (fewer
/// than 4 faces, an invalid index, a repeated vertex, an open or non-manifold edge, a self-intersection), and
/// pectus::InputError for a missing tissue label.
void checkSurfaceForTetgen(const SurfaceMesh& s);

/// Tetrahedralises the volume bounded by the surface (checkSurfaceForTetgen first; TetGen would crash on
/// self-intersecting input). Each tet is labelled with the tissue of the surface face nearest to its
/// centroid (region points are not needed, so a single closed surface whose faces carry the labels —
/// as the rib cage generator writes it — works; for thin parts the nearest face is the part's own
/// surface). Input vertices keep their indices: surface vertex i is mesh node i, at its input position and
/// in at least one tet (TetGen numbers the points it keeps consecutively and drops a point in no face
/// outside the volume or a duplicate: the nodes are renumbered back, and a vertex TetGen left out or no tet
/// uses throws TopologyError). `tetFace`, if given, receives that nearest surface face per tet (e.g. to carry
/// further face labels onto the tets). When TetGen fails (TopologyError: it refused the surface, stopped on an
/// assertion, ran past the time limit, made a flat tet...; InputError for options validate refuses), the message also names the surface's smallest feature if it is
/// under 1e-3 of the median edge (smallestFeature), which is where such failures come from.
TetMesh tetrahedralize(const SurfaceMesh& s, const TetgenOptions& opt = {}, std::vector<int>* tetFace = nullptr);

/// TetGen's quality refinement does not terminate for a radius-edge bound below this (its manual)
constexpr double kMinRadiusEdgeRatio = 1.2;
/// Throws InputError for options TetGen cannot run: an order other than 1 or 2, a radius-edge bound in
/// (0, kMinRadiusEdgeRatio) or not finite, a maximum volume not finite. tetrahedralize calls it first.
void validate(const TetgenOptions& opt);

/// The surface's smallest feature: its shortest edge, or the smallest distance from a vertex to a face it
/// is not a corner of (two sheets that nearly touch, a vertex nearly on another face, a sliver), whichever
/// is smaller, beside the median edge length. A feature far below the edges (near-duplicate vertices, a
/// pinch) is what TetGen's refinement fails on: when it fails, tetrahedralize's TopologyError names this
/// feature if it is under 1e-3 of the median edge. Grid search; vertex and face are -1 for an empty surface.
struct SurfaceFeature {
  int vertex = -1;  ///< the vertex near a face, or the short edge's first vertex
  int other = -1;   ///< the short edge's second vertex; -1 for a vertex near a face
  int face = -1;    ///< the face the vertex is near; -1 for a short edge
  double size = std::numeric_limits<double>::infinity();  ///< edge length or distance, mm
  double medianEdge = 0;                                   ///< mm
};
SurfaceFeature smallestFeature(const SurfaceMesh& s);

/// Index of the face of s nearest to each query point (uniform grid search).
std::vector<int> nearestFaces(const SurfaceMesh& s, const std::vector<Eigen::Vector3d>& points);

}  // namespace pectus::fe
