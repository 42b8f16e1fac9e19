// The cores' triangle surface: vertices and triangles as index arrays in double precision, and its
// topology (edges, vertex-to-faces, boundary, manifold, closed, components), built once from it.
// Host-free and vcg-free (Eigen only); the conversion from and to MeshLab's CMeshO is in
// pectus/surface_cmesh.h.
#pragma once
#include <array>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace pectus {

/// A triangle surface (or soup): positions in mm and vertex-index triples.
struct Surface {
  std::vector<Eigen::Vector3d> V;
  std::vector<std::array<int, 3>> F;
  bool empty() const { return F.empty(); }
};

/// The topology of a Surface, built once. It never throws: what it finds (an index out of range, edges in
/// more than two faces, vertices whose faces form more than one fan, collapsed edges) is recorded for the
/// caller to judge, each caller with its own message. When a face has a vertex index out of range nothing
/// else is built.
class Topology {
 public:
  struct Edge {
    int a, b;    ///< vertices, a < b
    int f0, f1;  ///< face*3 + local edge (local edge l is opposite local vertex l); f1 = -1 with one face
    int faces;   ///< number of faces that use the edge (> 2: a non-manifold edge)
  };

  explicit Topology(const Surface& s);

  /// the first face (in face order) with a vertex index out of range and that index; -1 if none
  int badFace = -1, badIndex = 0;

  std::vector<int> vfStart, vf;              ///< CSR vertex -> faces (a face with a repeated vertex once per corner)
  std::vector<Edge> edges;                   ///< sorted by (a, b); a face's repeated-vertex "edge" is not an edge
  std::vector<int> edgeFaceStart, edgeFace;  ///< CSR edge -> face*3 + local edge, ascending
  std::vector<std::array<int, 3>> faceEdge;  ///< per face: edge id of local edge l (-1 for a collapsed edge)
  std::vector<char> boundary;                ///< per vertex: on an edge with one face
  /// per vertex, by counting: its edges are not those of one fan (one cycle: as many edges as faces; or one
  /// chain: one edge more, two of them boundary edges). The count misses a closed fan that touches another
  /// fan at the vertex, which `fans` finds. Vertices of a face with a repeated vertex are not judged.
  std::vector<char> nonManifoldVertex;
  /// per vertex: how many fans its faces form, by walking them (faces that share an edge at the vertex are
  /// in one fan); 0 for a vertex no face uses. More than one: two sheets touch at the vertex (a pinch).
  std::vector<int> fans;
  /// per vertex: how many local edges of faces with a repeated vertex collapse onto it (a face (a, a, b)
  /// gives one at a, a face (a, a, a) three). They are not in `edges`; see edgeUse().
  std::vector<int> collapsedEdges;

  /// How many edges are used by one face and by more than two, counted as a table keyed by every face's
  /// three local edges (a, b) counts them: the edges, and per vertex with collapsed edges one "(v, v)" key
  /// used collapsedEdges[v] times (so a single degenerate face adds a boundary "edge").
  struct EdgeUse {
    std::size_t once = 0, moreThanTwice = 0;
  };
  EdgeUse edgeUse() const;

  std::size_t boundaryEdges() const;
  std::size_t nonManifoldEdges() const;
  /// every edge in exactly two faces and no vertex in nonManifoldVertex (no face at all: false)
  bool closedManifold() const;
  /// the faces (face*3 + local) of edge e
  const int* edgeFacesBegin(int e) const { return edgeFace.data() + edgeFaceStart[std::size_t(e)]; }
  const int* edgeFacesEnd(int e) const { return edgeFace.data() + edgeFaceStart[std::size_t(e) + 1]; }
  /// connected pieces: per face its component id (faces sharing a vertex are connected); returns their number
  int components(std::vector<int>& faceComponent) const;

 private:
  void countFans(const Surface& s);
};

}  // namespace pectus
