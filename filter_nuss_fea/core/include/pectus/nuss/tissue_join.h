// One layer per tissue (as CT segmentation tools export them: closed surfaces of the ribs, the costal
// cartilages and the sternum that overlap or touch at the costochondral junctions and the sternum) joined
// into one conforming volume for the Nuss FE analysis. Host-free (vcglib + CGAL, no Qt).
//
// Join: every layer is checked (faces, closed 2-manifold, no self-intersection; orientation is fixed),
// then the layers are merged by CGAL's corefinement union (Polygon_mesh_processing::
// corefine_and_compute_union) into one closed surface. Its faces take the tissue and part of the input
// surface they lie on. Tets (after TetGen) take the tissue of the input solid containing their centroid;
// where solids overlap, the one the centroid lies deeper in (farther from its surface), so the interface
// sits in the middle of the overlap as it does at a real junction; ties: cartilage, sternum, bone —
// CageSurface::labelTets. (Letting cartilage win the whole overlap would lengthen every costal cartilage
// by the overlaps at both of its ends and make the joined cage 34 % softer than the one-surface cage.)
//
// Parts: a layer carrying face labels (as 'Pectus: Create Rib Cage' writes them) keeps its
// parts. Otherwise: each connected piece of a bone layer is the rib of the nearest costovertebral joint
// landmark (100*side + rib); a cartilage face belongs to the rib nearest to it (a bone layer labelled as
// the vertebral column, part 400, is never that rib); sternum faces are the sternum body (302). A layer
// labelled throughout as the vertebral column keeps part 400 on its faces and on the tets it contains.
#pragma once
#include <string>
#include <vector>

#include "pectus/nuss/nuss_analysis.h"

namespace pectus::nuss {

struct TissueLayer {
  std::string name;                   ///< layer name (messages, and the tissue when `tissue` is Unknown)
  const CMeshO* mesh = nullptr;
  Tissue tissue = Tissue::Unknown;    ///< Unknown: from the name, else from the layer's own face labels
};

/// The tissue a layer name says (case-insensitive): "cartilag" -> cartilage; "stern", "manubr", "xiph"
/// -> sternum; "rib", "bone", "costa" -> bone (checked in this order, so "costal cartilage" is cartilage);
/// else Unknown.
Tissue tissueFromName(const std::string& name);

struct JoinStats {
  int layers = 0;
  double sumVolume = 0;    ///< mm^3, the layers' volumes added
  double unionVolume = 0;  ///< mm^3, of the joined surface
  int components = 0;      ///< connected pieces of the joined surface
};

/// Joins the layers into `joined` (labelled: writeFaceLabels) and returns its CageSurface with labelTets
/// set (containment rule above). Throws TopologyError naming the layer when one has no faces, is open,
/// non-manifold or self-intersecting, or when the union is non-manifold; InputError for a non-finite
/// coordinate, when a layer's tissue cannot be told, or when there is no bone or no cartilage layer.
CageSurface joinTissueLayers(const std::vector<TissueLayer>& layers, const std::vector<Landmark>& landmarks, CMeshO& joined,
                             JoinStats* stats = nullptr);

}  // namespace pectus::nuss
