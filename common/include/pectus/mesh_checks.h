// Checks every filter runs on its input before touching it, so bad input ends in a message
// naming what is wrong instead of a crash or NaN.
#pragma once
#include <string>

#include "pectus/cmesh.h"

namespace pectus {

struct MeshReport {
  std::size_t vertices = 0;          ///< live vertices
  std::size_t faces = 0;             ///< live faces
  std::size_t unreferencedVertices = 0;
  std::size_t nonFiniteVertices = 0; ///< NaN or Inf coordinates
  std::size_t degenerateFaces = 0;   ///< zero area or repeated vertex
  std::size_t duplicateFaces = 0;    ///< faces with the same three vertices as an earlier face
  /// edges with one face, and with three or more; a degenerate face's collapsed edge counts (Topology::edgeUse)
  std::size_t boundaryEdges = 0;
  std::size_t nonManifoldEdges = 0;
  /// vertices whose edges and faces do not count as one fan (the count of Topology::nonManifoldVertex, with
  /// the collapsed edges)
  std::size_t nonManifoldVertices = 0;
  bool closed() const { return faces > 0 && boundaryEdges == 0 && nonManifoldEdges == 0; }
  std::string summary() const;
};

MeshReport inspectMesh(const CMeshO& m);

struct MeshRequirements {
  bool faces = true;          ///< at least one face (else: "points only" / "empty")
  bool finite = true;         ///< no NaN/Inf coordinates
  bool edgeManifold = false;  ///< no edge with more than two faces
  bool vertexManifold = false;
  bool closed = false;        ///< no boundary edge
  bool noDegenerate = false;  ///< no zero-area face
};

/// Throws naming the first requirement `m` fails; `layer` names the layer in the message: InputError for
/// NaN/Inf coordinates, TopologyError for the others (empty, no faces, duplicate faces, non-manifold edges
/// or vertices, zero-area faces, open). The mesh's topology (an edge sort, the largest cost) is built only
/// for the edge, vertex and closed requirements; without them the report's topological counts stay 0.
MeshReport requireMesh(const CMeshO& m, const MeshRequirements& req, const std::string& layer);

}  // namespace pectus
