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

/// Quality of one element from vertex positions X: alpha (eq. 3-20) or beta (eq. 3-23, own normal).
double elementQuality(const Element& e, const std::vector<Vec3>& X);
/// Quality of every element (in parallel; the same result for any thread count).
std::vector<double> elementQualities(const std::vector<Element>& elements, const std::vector<Vec3>& X);
/// Each element's value on its one or two faces; faces of no element (deleted) get 0.
std::vector<double> spreadToFaces(const std::vector<Element>& elements, const std::vector<double>& perElement,
                                  std::size_t faceCount);

}  // namespace pectus
