// Per-element quality of a triangle or quad mesh: alpha (eq. 3-20) for triangles, Knupp's beta
// (eq. 3-23) for quads stored as faux-edge triangle pairs.
#pragma once
#include <vector>

#include "pectus/elements.h"
#include "pectus/quality.h"

namespace pectus {

struct ElementQuality {
  ElementMesh mesh;
  std::vector<double> perElement;  ///< alpha or beta per element
  std::vector<double> perFace;     ///< the element's value on each face (deleted faces: 0)
  QualityStats stats;              ///< over elements
};

ElementQuality computeElementQuality(const CMeshO& m, ElementKind kind, int histogramBins = 10);

}  // namespace pectus
