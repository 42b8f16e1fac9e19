// The one self-intersection check of the project: CGAL's Polygon_mesh_processing::self_intersections
// (exact predicates) on a triangle surface given as points + triangles. Faces sharing a vertex or an
// edge are tested too (a fold through a neighbour counts), and a degenerate face (three collinear
// points) is reported as intersecting itself. Used by the rib cage generator (after every decimation),
// the FE mesher (before TetGen, which crashes on self-intersecting input), the tissue-layer join, the
// patient import and the smoothers (no node move may make two faces cross).
// Host-free: Eigen in, indices out (CGAL stays inside the .cpp).
#pragma once
#include <array>
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace pectus {

/// A pair of intersecting triangles (indices into the triangle list, a <= b; a == b: a degenerate face).
struct FacePair {
  int a = -1, b = -1;
};

/// Every pair of triangles of the surface that intersect other than along their shared edge or vertex,
/// sorted, the degenerate faces first. The triangles must form a 2-manifold surface (closed or not; orientation is fixed here, and
/// a vertex where two sheets touch is split first); an index out of range or a triangle repeating a
/// vertex is reported as degenerate (a == b).
std::vector<FacePair> selfIntersections(const std::vector<Eigen::Vector3d>& points,
                                        const std::vector<std::array<int, 3>>& triangles);

/// The same check for one set of triangles at several positions of its points (a smoother's input and its
/// result): the orientation and the mesh are built once, each call only moves the points.
class SelfIntersections {
 public:
  SelfIntersections(std::size_t numPoints, const std::vector<std::array<int, 3>>& triangles);
  ~SelfIntersections();
  SelfIntersections(const SelfIntersections&) = delete;
  SelfIntersections& operator=(const SelfIntersections&) = delete;
  /// the pairs at these positions (points.size() == numPoints), as selfIntersections gives them (it moves
  /// the mesh's points: one call at a time); a mesh of 4000 faces or more is checked in two halves on two
  /// threads
  std::vector<FacePair> operator()(const std::vector<Eigen::Vector3d>& points);
  /// the pairs of operator() that have one of `triangles` (indices into the triangle list) in them: only
  /// the faces whose bounding box meets one of theirs are tested, so a check after a few local changes
  /// costs a fraction of the whole
  std::vector<FacePair> involving(const std::vector<int>& triangles, const std::vector<Eigen::Vector3d>& points);

 private:
  struct Mesh;
  bool buildAsGiven(std::size_t numPoints, const std::vector<std::vector<std::size_t>>& polys);
  void moveTo(const std::vector<Eigen::Vector3d>& points);
  /// the mesh's crossing pairs among `faces` (all faces if null) as triangle pairs, after `out`'s
  /// degenerate ones, sorted as operator() sorts them
  std::vector<FacePair> pairs(const std::vector<std::size_t>* faces, std::vector<FacePair> out) const;
  std::unique_ptr<Mesh> mesh_;
  std::vector<FacePair> degenerate_;  // triangles repeating a vertex or pointing outside the points
  std::vector<int> faceOf_;           // mesh face -> triangle
  std::vector<int> meshFace_;         // triangle -> mesh face (-1: degenerate)
};

/// The triangles (sorted, unique indices) taking part in any of the pairs.
std::vector<int> facesOf(const std::vector<FacePair>& pairs);

}  // namespace pectus
