// MeshLab adapter of the rib cage generator (core/: pectus/ribcage): 'Pectus: Create Rib Cage'. Maps
// parameters, the new layers, progress, errors and results; no algorithm here.
#include "filter_ribcage.h"

#include <chrono>

#include "pectus/errors.h"
#include "pectus/labels.h"
#include "pectus/ribcage/haller.h"
#include "pectus/ribcage/ribcage.h"

using pectus::ml::FilterContext;
using pectus::ml::fmt;
using pectus::ml::num;
using pectus::ml::addFloat;
using pectus::ml::addInt;
using pectus::ParamRange;
namespace rc = pectus::ribcage;

namespace {
// The rib cage's ranges that depend on other parameters (validate() checks them exactly): the declared
// range is what the bounds allow for any chest, from the same constants.
constexpr ParamRange kChestDepthEnvelope{rc::kChestDepthShare.lo * rc::kChestWidthRange.lo,
                                         rc::kChestDepthShare.hi * rc::kChestWidthRange.hi};
constexpr ParamRange kFunnelWidthEnvelope{rc::kFunnelMinSize, rc::kChestWidthRange.hi};
constexpr ParamRange kFunnelHeightEnvelope{rc::kFunnelMinSize, rc::kFunnelHeightShare * rc::kSpineHeightRange.hi};
constexpr ParamRange kFunnelCenterXEnvelope{-rc::kFunnelCenterXShare * rc::kChestWidthRange.hi,
                                            rc::kFunnelCenterXShare * rc::kChestWidthRange.hi};
}  // namespace

FilterRibCagePlugin::FilterRibCagePlugin() {
  pectus::ml::FilterSpec s;
  s.id = FP_CREATE_RIBCAGE;
  s.name = "Pectus: Create Rib Cage";
  s.pythonName = "create_pectus_excavatum_rib_cage";
  s.info =
      "A parametric child's rib cage with pectus excavatum (thesis ch. 6): labelled ribs, cartilages and "
      "sternum, and a landmark layer.";
  s.doc = "create_ribcage";
  s.cls = pectus::ml::HostFilter::MeshCreation;
  s.arity = pectus::ml::HostFilter::NONE;
  s.needsCurrentMesh = false;
  s.postCondition = MeshModel::MM_FACECOLOR | MeshModel::MM_FACEQUALITY | MeshModel::MM_VERTQUALITY;
  addFilter(this, s);

}

void FilterRibCagePlugin::initParameters(int id, const MeshDocument&, RichParameterList& par) {
  if (id == FP_CREATE_RIBCAGE) initCreateRibCage(par);
}

void FilterRibCagePlugin::run(int id, FilterContext& ctx) {
  if (id != FP_CREATE_RIBCAGE) throw std::logic_error("unknown filter id");
  runCreateRibCage(ctx);
}

void FilterRibCagePlugin::initCreateRibCage(RichParameterList& par) {
  const pectus::ribcage::RibCageParams d;
  par.addParam(RichEnum("sizeMode", 0, QStringList() << "From age" << "Explicit dimensions", "Size",
                        "From age: every dimension from the age. Explicit: the width, depth and spine height below."));
  addFloat(par, "age", d.age, "Age (years)",
           "The child's age (thesis patients: 5-8).", rc::kAgeRange);
  addFloat(par, "chestWidth", 181.0f, "Chest inner width (mm)",
           "Explicit size: widest inner transverse diameter of the cage.", rc::kChestWidthRange);
  addFloat(par, "chestDepth", 74.0f, "Chest depth (mm)",
           "Explicit: sternum-vertebra distance at the jugular notch, "
           + num(rc::kChestDepthShare.lo) + "-" + num(rc::kChestDepthShare.hi) + " x chest width.",
           kChestDepthEnvelope);
  addFloat(par, "spineHeight", 172.0f, "Thoracic spine height (mm)",
           "Explicit size: T1-T12.", rc::kSpineHeightRange);
  addInt(par, "ribPairs", d.ribPairs, "Rib pairs",
         "Ribs 11 and 12 are floating.", rc::kRibPairsRange);
  addFloat(par, "hallerIndex", d.hallerIndex, "Pectus (Haller) index",
           "Transverse diameter / least sternum-vertebra distance; normal ~2.5, pectus > 3.25.", rc::kHallerIndexRange);
  addFloat(par, "funnelCenterX", d.funnelCenterX, "Funnel centre, lateral (mm)",
           "Funnel centre offset (+ = patient's left), |x| <= " + num(rc::kFunnelCenterXShare) + " x funnel width.",
           kFunnelCenterXEnvelope);
  addFloat(par, "funnelCenterZ", d.funnelCenterZ, "Funnel centre, along sternum",
           "0 = jugular notch, 1 = xiphisternal junction; 1.1 (default): lower sternum end.", rc::kFunnelCenterZRange);
  addFloat(par, "funnelWidth", d.funnelWidth, "Funnel width (mm)",
           "Transverse extent of the depression, up to the chest's inner width.", kFunnelWidthEnvelope);
  addFloat(par, "funnelHeight", d.funnelHeight, "Funnel height (mm)",
           "Vertical extent of the depression, up to " + num(rc::kFunnelHeightShare) + " x spine height.",
           kFunnelHeightEnvelope);
  addFloat(par, "edgeLength", d.edgeLength, "Target edge length (mm)",
           "Resolution: 5-6 mm gives a few thousand faces (tests), 2 mm ~80k, "
           "1 mm ~300k.", rc::kEdgeLengthRange);
  par.addParam(RichEnum("cartilageSection", 0, QStringList() << "The rib's" << "Circular, twice the rib's area (CT)",
                        "Costal cartilage section",
                        "The rib's: its elliptic section. Circular, twice the rib's area: matches CT, 3.5-7x stiffer."));
  par.addParam(RichEnum("output", 0, QStringList() << "One labelled surface" << "One layer per tissue (as CT segmentation)",
                        "Output",
                        "One labelled surface (tissue per face), or closed 'ribs', 'costal cartilage', 'sternum' layers."));
}

void FilterRibCagePlugin::runCreateRibCage(FilterContext& ctx) {
  pectus::ribcage::RibCageParams p;
  p.fromAge = ctx.enumIn("sizeMode", 2) == 0;
  // validate() checks every one against the constants the declaration uses (and the ranges that depend on
  // other parameters exactly), with messages that give the unit and the dependence; the size parameters
  // of the other size mode are not used
  p.age = ctx.floatCheckedByCore("age");
  p.chestWidth = ctx.floatCheckedByCore("chestWidth");
  p.chestDepth = ctx.floatCheckedByCore("chestDepth");
  p.spineHeight = ctx.floatCheckedByCore("spineHeight");
  p.ribPairs = ctx.intCheckedByCore("ribPairs");
  p.hallerIndex = ctx.floatCheckedByCore("hallerIndex");
  p.funnelCenterX = ctx.floatCheckedByCore("funnelCenterX");
  p.funnelCenterZ = ctx.floatCheckedByCore("funnelCenterZ");
  p.funnelWidth = ctx.floatCheckedByCore("funnelWidth");
  p.funnelHeight = ctx.floatCheckedByCore("funnelHeight");
  p.edgeLength = ctx.floatCheckedByCore("edgeLength");
  p.cartilageSection = ctx.enumIn("cartilageSection", 2) == 1 ? pectus::ribcage::CartilageSection::Ct
                                                               : pectus::ribcage::CartilageSection::Rib;
  pectus::ribcage::validate(p);  // before any layer is added

  const bool perTissue = ctx.enumIn("output", 2) == 1;
  const auto t0 = std::chrono::steady_clock::now();
  pectus::OwnedMesh cage;
  std::array<pectus::OwnedMesh, 3> tissues;
  pectus::ribcage::RibCageStats st;
  auto prog = [&](int pc, const char* w) { ctx.progress(pc, w); };
  const auto lms = perTissue ? pectus::ribcage::generateTissueLayers(p, tissues, &st, prog)
                             : pectus::ribcage::generateRibCage(p, cage, &st, prog);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  auto addLabelled = [&](const QString& name, CMeshO& src) -> MeshModel& {
    MeshModel& mm = ctx.addLayer(name);
    mm.updateDataMask(MeshModel::MM_FACECOLOR | MeshModel::MM_FACEQUALITY);
    pectus::copyLabelledMesh(mm.cm, src);
    vcg::tri::UpdateNormal<CMeshO>::PerVertexNormalizedPerFaceNormalized(mm.cm);
    vcg::tri::UpdateBounding<CMeshO>::Box(mm.cm);
    return mm;
  };
  std::optional<pectus::ribcage::HallerMeasure> measured;
  int faces = 0, vertices = 0;
  if (perTissue) {
    for (int k = 0; k < 3; ++k) {
      const MeshModel& mm = addLabelled(pectus::ribcage::kTissueLayerNames[std::size_t(k)], tissues[std::size_t(k)]);
      faces += mm.cm.fn, vertices += mm.cm.vn;
    }
  } else {
    measured = pectus::ribcage::measureHaller(cage);
    const MeshModel& mm = addLabelled("pectus rib cage", cage);
    faces = mm.cm.fn, vertices = mm.cm.vn;
  }

  MeshModel& lm = ctx.addLayer("ribcage landmarks", false);
  lm.updateDataMask(MeshModel::MM_VERTQUALITY);
  pectus::writeLandmarks(lm.cm, lms);
  vcg::tri::UpdateBounding<CMeshO>::Box(lm.cm);

  const auto& d = st.dims;
  const std::array<double, 2> cartilage = pectus::ribcage::cartilageDiameters(d, p.cartilageSection);
  ctx.log("Rib cage" + std::string(perTissue ? " (3 tissue layers)" : "") + ": " + std::to_string(faces) + " faces, " +
          std::to_string(vertices) + " vertices, " +
          std::to_string(p.ribPairs) + " rib pairs; Haller index requested " + fmt(p.hallerIndex) +
          ", model " + fmt(st.hallerModel) + ", measured on mesh " +
          (measured ? fmt(measured->index) : std::string("n/a")) + " (T " +
          (measured ? fmt(measured->transverse) : std::string("n/a")) + " mm / AP " +
          (measured ? fmt(measured->ap) : std::string("n/a")) + " mm); funnel depth " + fmt(st.funnelDepth) +
          " mm; dimensions: chest width " + fmt(d.chestWidth) + " depth " + fmt(d.chestDepth) + " spine " +
          fmt(d.spineHeight) + " sternum " + fmt(d.sternumLength) + " mm, rib section " + fmt(d.ribHeight) + " x " +
          fmt(d.ribThickness) + " mm, costal cartilage section " + fmt(cartilage[0]) + " x " + fmt(cartilage[1]) +
          " mm; " + std::to_string(lms.size()) +
          " landmarks; " + fmt(secs, 3) + " s");
  auto& values = ctx.results();
  values.set("faces", faces);
  values.set("vertices", vertices);
  values.set("rib_pairs", p.ribPairs);
  values.set("haller_index_requested", p.hallerIndex);
  values.set("haller_index_model", st.hallerModel);
  if (measured) {  // the single-layer cage, measured on its mesh
    values.set("haller_index_measured", measured->index);
    values.set("transverse_mm", measured->transverse);
    values.set("ap_mm", measured->ap);
  }
  values.set("funnel_depth_mm", st.funnelDepth);
  values.set("chest_width_mm", d.chestWidth);
  values.set("chest_depth_mm", d.chestDepth);
  values.set("spine_height_mm", d.spineHeight);
  values.set("sternum_length_mm", d.sternumLength);
  values.set("rib_height_mm", d.ribHeight);
  values.set("rib_thickness_mm", d.ribThickness);
  values.set("cartilage_width_mm", cartilage[0]);
  values.set("cartilage_thickness_mm", cartilage[1]);
  values.set("landmarks", lms.size());
  values.set("seconds", secs);
}
