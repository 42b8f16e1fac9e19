#include "pectus/labels.h"

#include <vcg/complex/allocate.h>
#include <vcg/complex/append.h>

namespace pectus {

namespace {
Rgb tissueColor(int t) {
  switch (Tissue(t)) {
    case Tissue::Bone: return kBoneColor;
    case Tissue::Cartilage: return kCartilageColor;
    case Tissue::Sternum: return kSternumColor;
    default: return Rgb{128, 128, 128};
  }
}
}  // namespace

void writeFaceLabels(CMeshO& m, const std::vector<int>& tissue, const std::vector<int>& part) {
  auto ht = vcg::tri::Allocator<CMeshO>::GetPerFaceAttribute<int>(m, kTissueAttr);
  auto hp = vcg::tri::Allocator<CMeshO>::GetPerFaceAttribute<int>(m, kPartAttr);
  if (!m.face.IsColorEnabled()) m.face.EnableColor();
  if (!m.face.IsQualityEnabled()) m.face.EnableQuality();
  for (std::size_t i = 0; i < m.face.size(); ++i) {
    const int t = i < tissue.size() ? tissue[i] : 0, p = i < part.size() ? part[i] : 0;
    ht[i] = t;
    hp[i] = p;
    const Rgb c = tissueColor(t);
    m.face[i].C() = vcg::Color4b(c.r, c.g, c.b, 255);
    m.face[i].Q() = float(t * 1000 + p);
  }
}

void copyLabelledMesh(CMeshO& dst, CMeshO& src) {
  vcg::tri::Append<CMeshO, CMeshO>::MeshCopy(dst, src);
  const auto l = readFaceLabels(src);
  if (!l) return;
  std::vector<int> tissue, part;
  for (std::size_t i = 0; i < src.face.size(); ++i)
    if (!src.face[i].IsD()) tissue.push_back(l->tissue[i]), part.push_back(l->part[i]);
  writeFaceLabels(dst, tissue, part);
}

std::optional<FaceLabels> readFaceLabels(const CMeshO& m) {
  FaceLabels out;
  out.tissue.assign(m.face.size(), 0);
  out.part.assign(m.face.size(), 0);
  if (vcg::tri::HasPerFaceAttribute(m, kTissueAttr)) {
    auto ht = vcg::tri::Allocator<CMeshO>::FindPerFaceAttribute<int>(const_cast<CMeshO&>(m), kTissueAttr);
    auto hp = vcg::tri::Allocator<CMeshO>::FindPerFaceAttribute<int>(const_cast<CMeshO&>(m), kPartAttr);
    for (std::size_t i = 0; i < m.face.size(); ++i) {
      out.tissue[i] = ht[i];
      out.part[i] = vcg::tri::HasPerFaceAttribute(m, kPartAttr) ? hp[i] : 0;
    }
    out.source = "face attributes";
  } else if (m.face.IsColorEnabled()) {
    for (std::size_t i = 0; i < m.face.size(); ++i) {
      const auto& c = m.face[i].cC();
      for (int t = 1; t <= 3; ++t) {
        const Rgb r = tissueColor(t);
        if (c[0] == r.r && c[1] == r.g && c[2] == r.b) out.tissue[i] = t;
      }
      if (m.face.IsQualityEnabled()) {
        const int code = int(m.face[i].cQ() + 0.5f);
        if (code / 1000 == out.tissue[i]) out.part[i] = code % 1000;
      }
    }
    out.source = "face colours";
  } else {
    return std::nullopt;
  }
  for (std::size_t i = 0; i < m.face.size(); ++i)
    if (!m.face[i].IsD() && out.tissue[i] == 0) return std::nullopt;
  return out;
}

std::vector<Landmark> readLandmarks(const CMeshO& layer) {
  std::vector<Landmark> out;
  for (const auto& v : layer.vert)
    if (!v.IsD()) out.push_back({int(v.cQ() + (v.cQ() >= 0 ? 0.5f : -0.5f)), toEigen(v.cP())});
  return out;
}

void writeLandmarks(CMeshO& layer, const std::vector<Landmark>& lms) {
  auto vi = vcg::tri::Allocator<CMeshO>::AddVertices(layer, lms.size());
  for (const auto& l : lms) {
    vi->P() = toPoint(l.p);
    vi->Q() = float(l.code);
    ++vi;
  }
}

std::optional<Eigen::Vector3d> findLandmark(const std::vector<Landmark>& lms, int code) {
  for (const auto& l : lms)
    if (l.code == code) return l.p;
  return std::nullopt;
}

std::string faceLabelProblem(const CMeshO& m) {
  if (!m.face.IsColorEnabled())
    return "the faces have neither the label attributes nor colours (saved without '-m fc fq', or never labelled)";
  std::size_t live = 0, off = 0;
  for (const auto& f : m.face) {
    if (f.IsD()) continue;
    ++live;
    bool hit = false;
    for (int t = 1; t <= 3; ++t) {
      const Rgb r = tissueColor(t);
      hit = hit || (f.cC()[0] == r.r && f.cC()[1] == r.g && f.cC()[2] == r.b);
    }
    off += hit ? 0 : 1;
  }
  return std::to_string(off) + " of " + std::to_string(live) +
         " face colours are not tissue colours (a filter that colours faces, e.g. 'Pectus: Element Quality' with "
         "'Colour by quality', overwrote the labels of a saved file: label before colouring, or keep the labelled copy)";
}

}  // namespace pectus
