// CMeshO <-> pectus::c1::TriMesh for the C1 surface core (deleted elements skipped).
#pragma once
#include <vector>

#include "pectus/c1_surface.h"
#include "pectus/cmesh.h"

namespace pectus::c1 {

/// Live vertices and faces of `m`; `vertexIndex`, if given, receives for each TriMesh vertex its index in m.vert.
TriMesh toTriMesh(const CMeshO& m, std::vector<int>* vertexIndex = nullptr);
/// Replaces the content of `m` with `t` (and per-vertex normals if given, same size as t.V).
void fromTriMesh(const TriMesh& t, CMeshO& m, const std::vector<Vec3>* normals = nullptr);

}  // namespace pectus::c1
