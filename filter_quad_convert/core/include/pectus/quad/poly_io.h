// Writes a triangle/quad mesh with real quads (MeshLab 2020.09 cannot: its OBJ/PLY exporters write the
// two triangles of every quad and its OFF exporter writes wrong indices for polygons).
#pragma once
#include <string>

#include "pectus/quad/poly_mesh.h"

namespace pectus::quad {

enum class PolyFormat { OBJ, OFF, VTK };

/// Writes `m` (ASCII, full float precision). OBJ: `v`/`f` records, 1-based. OFF: "OFF", counts, vertices,
/// "n i j k [l]". VTK: legacy "POLYDATA" with POINTS and POLYGONS. Throws IOError if the file cannot be
/// written (missing folder, no permission, disk full).
void writePolyMesh(const std::string& path, const PolyMesh& m, PolyFormat format);

}  // namespace pectus::quad
