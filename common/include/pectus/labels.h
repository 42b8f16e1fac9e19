// The project's anatomical conventions, shared by the rib cage generator (filter_nuss_fea), the FE
// analysis (filter_nuss_fea) and the thoracic volume filters (filter_thoracic_volume).
//
// Frame: millimetres; +z superior (towards the head), +y anterior (towards the sternum), +x the
// patient's left. The spine (vertebral bodies' anterior surface) is near x = 0, y = 0.
//
// Tissue labels live in memory as named per-face int attributes (vcg custom attributes, kept by the
// adapter's rollback): "pectus_tissue" (Tissue) and "pectus_part" (anatomical part id). So that they
// survive saving to PLY, the generator also writes them as the face colour (tissue palette below,
// saved with `-m fc`) and the face quality (tissue * 1000 + part, saved with `-m fq`). Readers use
// the attribute when present, else the face colour palette (exact match), else fail with a message.
//
// Landmarks live in a separate point layer (label ends in "landmarks"): one vertex per landmark,
// its per-vertex quality = the landmark code below (saved with `-m vq`).
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "pectus/cmesh.h"

namespace pectus {

enum class Tissue : int { Unknown = 0, Bone = 1, Cartilage = 2, Sternum = 3 };

// Anatomical part id: ribs and their cartilages 100*side + rib number (side 1 = right, 2 = left),
// sternum parts 301 manubrium, 302 body, 303 xiphoid; 400 the vertebral column (tissue bone), present only
// when 'Pectus: Prepare Patient Rib Cage' keeps it as the fixed support: the FE analysis fixes every node of its
// tets, and the thoracic volume filters leave its faces out (the volume is the one inside the ribs).
inline int ribPart(int side, int rib) { return 100 * side + rib; }
constexpr int kManubrium = 301, kSternumBody = 302, kXiphoid = 303;
constexpr int kVertebralColumn = 400;

// Landmark codes (vertex quality of the landmarks layer)
//  100*side + k     costovertebral joint of rib k (side 1 right, 2 left): centre of the rib's posterior end cap
//  500              lower end of the sternum (where the thesis applies the elevating force Fe)
//  501              deepest point of the pectus funnel (on the anterior sternal surface)
//  502              upper end of the sternum (jugular notch)
//  503              anterior surface of the vertebral body at the level of the deepest point (for the Haller index)
//  600 + 10*side + s  a Nuss bar's exit point at the mid-axillary line in intercostal space s (between ribs s and s+1)
//  700              dome of the diaphragm height (lower limit of the thoracic volume), 701 lung apex height
inline int cvjLandmark(int side, int rib) { return 100 * side + rib; }
constexpr int kSternumLowerEnd = 500, kFunnelDeepest = 501, kSternumUpperEnd = 502, kVertebraAtDeepest = 503;
inline int barExitLandmark(int side, int space) { return 600 + 10 * side + space; }
constexpr int kDiaphragmDome = 700, kLungApex = 701;

struct Rgb { unsigned char r, g, b; };
// tissue palette of the face colours (exact values; a reader matches them exactly)
constexpr Rgb kBoneColor{235, 222, 190}, kCartilageColor{90, 160, 235}, kSternumColor{215, 110, 95};

inline const char* tissueName(Tissue t) {
  switch (t) {
    case Tissue::Bone: return "bone";
    case Tissue::Cartilage: return "cartilage";
    case Tissue::Sternum: return "sternum";
    default: return "unknown";
  }
}

constexpr const char* kTissueAttr = "pectus_tissue";
constexpr const char* kPartAttr = "pectus_part";

/// Writes the labels as attributes, face colour and face quality (enables face colour/quality on m).
void writeFaceLabels(CMeshO& m, const std::vector<int>& tissue, const std::vector<int>& part);

/// dst = the live part of src (vcg MeshCopy: deleted elements dropped, order kept) with src's face labels
/// (MeshCopy does not copy named attributes): the i-th live face of src is face i of dst.
void copyLabelledMesh(CMeshO& dst, CMeshO& src);

/// Per-face labels of m (size m.face.size()): from the attributes, else from the face colour
/// palette and face quality code. std::nullopt if neither is there or a live face has no label.
struct FaceLabels { std::vector<int> tissue, part; std::string source; };
std::optional<FaceLabels> readFaceLabels(const CMeshO& m);
/// Why readFaceLabels finds no labels, for messages: no colour/attribute at all, or how many face
/// colours are outside the tissue palette (a filter colouring faces, e.g. by quality, overwrote them).
std::string faceLabelProblem(const CMeshO& m);

struct Landmark { int code; Eigen::Vector3d p; };
/// Landmarks of a landmark layer (vertex quality = code)
std::vector<Landmark> readLandmarks(const CMeshO& landmarkLayer);
void writeLandmarks(CMeshO& layer, const std::vector<Landmark>& lms);
std::optional<Eigen::Vector3d> findLandmark(const std::vector<Landmark>& lms, int code);

}  // namespace pectus
