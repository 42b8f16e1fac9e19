// Quadric edge-collapse decimation of a closed CMeshO to a target face count, topology preserving
// (link condition), with normal-flip and triangle-quality checks.
#pragma once
#include "pectus/cmesh.h"

namespace pectus::ribcage {
void decimateQuadric(CMeshO& m, int targetFaces);
}
