#include "filter_nuss_fea.h"

#include <chrono>

#include "pectus/errors.h"
#include "pectus/labels.h"
#include "haller.h"
#include "ribcage.h"

using pectus::ml::FilterContext;
using pectus::ml::fmt;

FilterNussFeaPlugin::FilterNussFeaPlugin() {
  pectus::ml::FilterSpec s;
  s.id = FP_CREATE_RIBCAGE;
  s.name = "Create Pectus Excavatum Rib Cage";
  s.info =
      "A parametric child's rib cage with pectus excavatum (thesis ch. 6, Table 6-1): 10-12 rib pairs "
      "(elliptic sections, sloping down from the costovertebral joints, widest at ribs 6-8), costal "
      "cartilages (ribs 1-7 to the sternum, 8-10 to the cartilage above) and a sternum (manubrium, body, "
      "xiphoid) depressed into a funnel whose depth reproduces the requested pectus (Haller) index "
      "= widest inner transverse diameter / smallest sternum-to-vertebra distance.<br>"
      "One watertight, manifold, self-intersection-free surface (implicit smooth union extracted by "
      "marching tetrahedra, decimated to the target edge length); ribs 11-12 float (own components).<br>"
      "Frame: mm, +x patient's left, +y anterior, +z superior, vertebral bodies' anterior surface at "
      "x = y = 0. Every face: tissue (face colour: bone / cartilage / sternum) and anatomical part "
      "(face quality = tissue*1000 + part; rib part = 100*side + rib, side 1 right, 2 left; "
      "301 manubrium, 302 body, 303 xiphoid). A second layer 'ribcage landmarks' holds one vertex "
      "per landmark (vertex quality = code: costovertebral joints 100*side+rib, 500 lower sternum end, "
      "501 deepest funnel point, 502 jugular notch, 503 vertebra at the deepest level, "
      "600+10*side+s bar exits at the mid-axillary line in intercostal space s = 4, 5, "
      "700 diaphragm dome height, 701 lung apex height).";
  s.cls = MeshFilterInterface::MeshCreation;
  s.arity = MeshFilterInterface::NONE;
  s.needsCurrentMesh = false;
  s.postCondition = MeshModel::MM_FACECOLOR | MeshModel::MM_FACEQUALITY | MeshModel::MM_VERTQUALITY;
  addFilter(this, s);
}

void FilterNussFeaPlugin::initParameters(int id, MeshDocument&, RichParameterList& par) {
  if (id == FP_CREATE_RIBCAGE) initCreateRibCage(par);
}

void FilterNussFeaPlugin::run(int id, FilterContext& ctx) {
  switch (id) {
    case FP_CREATE_RIBCAGE: runCreateRibCage(ctx); break;
    default: throw std::logic_error("unknown filter id");
  }
}

void FilterNussFeaPlugin::initCreateRibCage(RichParameterList& par) {
  const pectus::ribcage::RibCageParams d;
  par.addParam(RichEnum("sizeMode", 0, QStringList() << "From age" << "Explicit dimensions", "Size",
                        "From age: every dimension from the child's age. Explicit: chest width, depth and "
                        "spine height below (rib and sternum sections still follow the equivalent age)."));
  par.addParam(RichFloat("age", float(d.age), "Age (years)", "5 to 17 years (thesis patients: 5-8)."));
  par.addParam(RichFloat("chestWidth", 181.0f, "Chest inner width (mm)",
                         "Explicit size: widest inner transverse diameter of the cage, 120-320 mm."));
  par.addParam(RichFloat("chestDepth", 74.0f, "Chest depth (mm)",
                         "Explicit size: sternum-to-vertebra distance without funnel at the jugular notch, "
                         "0.25-0.7 x chest width."));
  par.addParam(RichFloat("spineHeight", 172.0f, "Thoracic spine height (mm)", "Explicit size: T1-T12, 120-320 mm."));
  par.addParam(RichInt("ribPairs", d.ribPairs, "Rib pairs", "10, 11 or 12 (ribs 11-12 are floating)."));
  par.addParam(RichFloat("hallerIndex", float(d.hallerIndex), "Pectus (Haller) index",
                         "Requested index: inner transverse diameter / smallest sternum-to-vertebra distance. "
                         "Normal ~2.5, pectus excavatum > 3.25 (thesis patients 3.6-5.3). The valid range "
                         "starts at the index of the same chest without funnel."));
  par.addParam(RichFloat("funnelCenterX", float(d.funnelCenterX), "Funnel centre, lateral (mm)",
                         "Lateral offset of the funnel centre (+ = patient's left), |x| <= 0.4 x funnel width."));
  par.addParam(RichFloat("funnelCenterZ", float(d.funnelCenterZ), "Funnel centre, along sternum",
                         "0 = jugular notch, 1 = xiphisternal junction (up to 1.2)."));
  par.addParam(RichFloat("funnelWidth", float(d.funnelWidth), "Funnel width (mm)",
                         "Transverse extent of the depression, 20 mm up to the chest's inner width."));
  par.addParam(RichFloat("funnelHeight", float(d.funnelHeight), "Funnel height (mm)",
                         "Vertical extent of the depression, 20 mm up to 0.8 x spine height."));
  par.addParam(RichFloat("edgeLength", float(d.edgeLength), "Target edge length (mm)",
                         "Resolution, 0.4-8 mm: 5-6 mm gives a few thousand faces (tests), 2 mm ~80k, "
                         "1 mm ~300k."));
}

void FilterNussFeaPlugin::runCreateRibCage(FilterContext& ctx) {
  pectus::ribcage::RibCageParams p;
  p.fromAge = ctx.enumIn("sizeMode", 2) == 0;
  const RichParameterList& par = ctx.params();
  // ranges are checked (with the messages naming each parameter) by the core
  p.age = par.getFloat("age");
  p.chestWidth = par.getFloat("chestWidth");
  p.chestDepth = par.getFloat("chestDepth");
  p.spineHeight = par.getFloat("spineHeight");
  p.ribPairs = par.getInt("ribPairs");
  p.hallerIndex = par.getFloat("hallerIndex");
  p.funnelCenterX = par.getFloat("funnelCenterX");
  p.funnelCenterZ = par.getFloat("funnelCenterZ");
  p.funnelWidth = par.getFloat("funnelWidth");
  p.funnelHeight = par.getFloat("funnelHeight");
  p.edgeLength = par.getFloat("edgeLength");
  pectus::ribcage::validate(p);  // before any layer is added

  const auto t0 = std::chrono::steady_clock::now();
  CMeshO cage;
  pectus::ribcage::RibCageStats st;
  const auto lms = pectus::ribcage::generateRibCage(p, cage, &st, [&](int pc, const char* w) { ctx.progress(pc, w); });
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto measured = pectus::ribcage::measureHaller(cage);

  MeshModel& mm = ctx.addLayer("pectus rib cage");
  mm.updateDataMask(MeshModel::MM_FACECOLOR | MeshModel::MM_FACEQUALITY);
  vcg::tri::Append<CMeshO, CMeshO>::MeshCopy(mm.cm, cage);
  // Append copies colour and quality but not the custom attributes: write the labels again
  if (auto l = pectus::readFaceLabels(cage)) pectus::writeFaceLabels(mm.cm, l->tissue, l->part);
  vcg::tri::UpdateNormal<CMeshO>::PerVertexNormalizedPerFaceNormalized(mm.cm);
  vcg::tri::UpdateBounding<CMeshO>::Box(mm.cm);

  MeshModel& lm = ctx.addLayer("ribcage landmarks", false);
  lm.updateDataMask(MeshModel::MM_VERTQUALITY);
  pectus::writeLandmarks(lm.cm, lms);
  vcg::tri::UpdateBounding<CMeshO>::Box(lm.cm);

  const auto& d = st.dims;
  ctx.log("Rib cage: " + std::to_string(mm.cm.fn) + " faces, " + std::to_string(mm.cm.vn) + " vertices, " +
          std::to_string(p.ribPairs) + " rib pairs; Haller index requested " + fmt(p.hallerIndex) +
          ", model " + fmt(st.hallerModel) + ", measured on mesh " +
          (measured ? fmt(measured->index) : std::string("n/a")) + " (T " +
          (measured ? fmt(measured->transverse) : std::string("n/a")) + " mm / AP " +
          (measured ? fmt(measured->ap) : std::string("n/a")) + " mm); funnel depth " + fmt(st.funnelDepth) +
          " mm; dimensions: chest width " + fmt(d.chestWidth) + " depth " + fmt(d.chestDepth) + " spine " +
          fmt(d.spineHeight) + " sternum " + fmt(d.sternumLength) + " mm; " + std::to_string(lms.size()) +
          " landmarks; " + fmt(secs, 3) + " s");
}

MESHLAB_PLUGIN_NAME_EXPORTER(FilterNussFeaPlugin)
