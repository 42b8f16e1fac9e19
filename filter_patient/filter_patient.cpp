// MeshLab adapter of the patient-data core (core/: pectus/patient): 'Pectus: Import CT Segmentation' and 'Prepare
// Patient Rib Cage'. Maps parameters, files, the visible layers, progress, errors and results; every decision
// is in the core.
#include "filter_patient.h"

#include <chrono>

#include <vcg/complex/algorithms/update/normal.h>
#include <vcg/complex/append.h>

#include "pectus/errors.h"
#include "pectus/format.h"
#include "pectus/labels.h"
#include "pectus/patient/ct_import.h"
#include "pectus/patient/prepare.h"

using pectus::ml::FilterContext;
using pectus::ml::fmt;
using pectus::ml::num;
using pectus::ml::addFloat;
using pectus::ml::addInt;

namespace {
using pectus::patient::kEdgeLengthRange;
using pectus::patient::kMinEdgeLength;
}  // namespace

FilterPatientPlugin::FilterPatientPlugin() {
  pectus::ml::FilterSpec c;
  c.id = FP_IMPORT_CT;
  c.name = "Pectus: Import CT Segmentation";
  c.pythonName = "import_ct_segmentation";
  c.info =
      "Reads a CT segmentation (a file or folder of STL, OBJ, PLY, OFF or NIfTI label maps) as one layer "
      "per structure.";
  c.doc = "import_ct_segmentation";
  c.cls = pectus::ml::HostFilter::MeshCreation;
  c.arity = pectus::ml::HostFilter::NONE;
  c.needsCurrentMesh = false;
  addFilter(this, c);

  pectus::ml::FilterSpec s;
  s.id = FP_PREPARE_PATIENT;
  s.name = "Pectus: Prepare Patient Rib Cage";
  s.pythonName = "prepare_patient_rib_cage";
  s.info =
      "Makes the visible layers of a patient's segmentation into the labelled rib cage and landmarks the "
      "analyses take.";
  s.doc = "prepare_patient_rib_cage";
  s.advanced = QStringList{"minVolume", "gridStep"};
  s.cls = pectus::ml::HostFilter::Remeshing;
  s.arity = pectus::ml::HostFilter::VARIABLE;
  s.needsCurrentMesh = false;
  s.postCondition = MeshModel::MM_FACECOLOR | MeshModel::MM_FACEQUALITY | MeshModel::MM_VERTQUALITY;
  addFilter(this, s);
}

void FilterPatientPlugin::initParameters(int id, const MeshDocument&, RichParameterList& par) {
  if (id == FP_IMPORT_CT) initImportCt(par);
  if (id == FP_PREPARE_PATIENT) initPreparePatient(par);
}

void FilterPatientPlugin::run(int id, FilterContext& ctx) {
  switch (id) {
    case FP_IMPORT_CT: runImportCt(ctx); break;
    case FP_PREPARE_PATIENT: runPreparePatient(ctx); break;
    default: throw std::logic_error("unknown filter id");
  }
}

void FilterPatientPlugin::initPreparePatient(RichParameterList& par) {
  const pectus::patient::PrepareOptions d;
  par.addParam(RichEnum("units", 0, QStringList() << "Automatic" << "Millimetres" << "Centimetres" << "Metres", "Units",
                        "Units of the input layers. Automatic: from the overall size (metres, centimetres or mm)."));
  par.addParam(RichEnum("frame", 0,
                        QStringList() << "Automatic (from the anatomy)" << "RAS (x right, y anterior, z superior)"
                                      << "LPS (x left, y posterior, z superior)" << "Project frame (x left, y anterior, z superior)",
                        "Frame",
                        "Axes of the input layers. Automatic: from the anatomy (sternum, ribs); or RAS, LPS, project frame."));
  addFloat(par, "minVolume", d.minVolume, "Fragment volume (mm^3)",
           "Smaller pieces are dropped as fragments (a child's rib: 2000-10000 mm^3).", pectus::patient::kMinVolumeRange);
  addFloat(par, "gridStep", d.gridStep, "Grid step (mm)",
           "Solid grid step, about the CT voxel size. Smaller: finer features, slower.",
           pectus::patient::kGridStepRange);
  addFloat(par, "edgeLength", d.edgeLength, "Target edge length (mm)",
           "Decimation edge length; 0 keeps every face, else at least " + num(kMinEdgeLength) + ". 4 mm suits the FE.",
           kEdgeLengthRange);
  par.addParam(RichEnum("spine", int(d.spine),
                        QStringList() << "cut at the costovertebral joints" << "keep as the fixed support", "Spine",
                        "Cut: left out, ribs cut at the joints (thesis). Keep: as bone (part 400), fixed by the FE analysis."));
  par.addParam(RichString("pickedPoints", "", "Picked points (.pp)",
                          "Optional MeshLab PickPoints file; points named by landmark code ('500') replace the automatic ones."));
}

void FilterPatientPlugin::runPreparePatient(FilterContext& ctx) {
  pectus::patient::PrepareOptions o;
  o.units = pectus::patient::Units(ctx.enumIn("units", 4));
  o.frame = pectus::patient::FrameMode(ctx.enumIn("frame", 4));
  o.minVolume = ctx.floatIn("minVolume");
  o.gridStep = ctx.floatIn("gridStep");
  o.edgeLength = ctx.floatIn("edgeLength");
  if (o.edgeLength > 0 && o.edgeLength < kMinEdgeLength)
    throw pectus::InputError("parameter 'edgeLength' (Target edge length) must be 0 or " + pectus::significantText(kMinEdgeLength) +
                             "-" + pectus::significantText(kEdgeLengthRange.hi) + " mm, got " + fmt(o.edgeLength));
  o.spine = pectus::patient::SpineMode(ctx.enumIn("spine", 2));
  const std::string pp = ctx.string("pickedPoints").trimmed().toStdString();
  if (!pp.empty()) {
    int skipped = 0;
    o.userLandmarks = pectus::patient::readPickedPoints(pp, &skipped);
    ctx.log("picked points: " + std::to_string(o.userLandmarks.size()) + " landmarks from " + pp +
            (skipped ? " (" + std::to_string(skipped) + " points without a code or inactive, skipped)" : std::string()));
  }
  std::vector<pectus::patient::InputLayer> layers;
  for (MeshModel* m : pectus::ml::meshes(ctx.doc())) {
    if (!m->isVisible()) continue;
    const std::string name = m->label().toStdString();
    if (m->cm.fn == 0) {
      if (m->cm.vn > 0 && QString::fromStdString(name).endsWith("user landmarks", Qt::CaseInsensitive)) {
        const auto user = pectus::readLandmarks(m->cm);
        o.userLandmarks.insert(o.userLandmarks.end(), user.begin(), user.end());
        ctx.log("'" + name + "': " + std::to_string(user.size()) + " user landmarks (vertex quality = code)");
      }
      continue;
    }
    if (pectus::readFaceLabels(m->cm)) {  // a cage this filter or the generator made: not a structure
      ctx.log("'" + name + "': already a labelled rib cage, left out");
      continue;
    }
    layers.push_back({name, &m->cm});
  }
  if (layers.empty())
    throw pectus::InputError("No visible layer with faces: import the segmentation first (File > Import Mesh, or 'Pectus: "
                             "Import CT Segmentation').");

  pectus::OwnedMesh cage;
  pectus::patient::PrepareResult r;
  try {
    r = pectus::patient::preparePatientCage(layers, o, cage, [&](int pc, const char* w) { ctx.progress(pc, w); });
  } catch (const pectus::patient::PrepareRefusal& e) {
    for (const auto& line : e.log) ctx.log(line);  // the decisions made before the refusal
    throw pectus::InputError(e.what());
  }

  MeshModel& mm = ctx.addLayer("patient rib cage");
  mm.updateDataMask(MeshModel::MM_FACECOLOR | MeshModel::MM_FACEQUALITY);
  pectus::copyLabelledMesh(mm.cm, cage);
  vcg::tri::UpdateNormal<CMeshO>::PerVertexNormalizedPerFaceNormalized(mm.cm);
  vcg::tri::UpdateBounding<CMeshO>::Box(mm.cm);
  MeshModel& lm = ctx.addLayer("patient landmarks", false);
  lm.updateDataMask(MeshModel::MM_VERTQUALITY);
  pectus::writeLandmarks(lm.cm, r.landmarks);
  vcg::tri::UpdateBounding<CMeshO>::Box(lm.cm);

  for (const auto& line : r.log) ctx.log(line);
  std::string placed;
  for (const auto& l : r.landmarks)
    placed += (placed.empty() ? "" : ", ") + std::to_string(l.code) + " (" + fmt(l.p.x(), 1) + " " + fmt(l.p.y(), 1) + " " +
              fmt(l.p.z(), 1) + ")";
  ctx.log("landmarks (code (x y z) mm, result frame): " + placed);
  const Eigen::Matrix4d& T = r.inputToModel;
  std::string t;
  for (int i = 0; i < 3; ++i)
    t += (i ? "; " : "") + fmt(T(i, 0), 4) + " " + fmt(T(i, 1), 4) + " " + fmt(T(i, 2), 4) + " " + fmt(T(i, 3), 2);
  ctx.log("input -> result transform (rows x y z: 3x3 | shift mm): " + t);
  ctx.log("Patient rib cage: " + std::to_string(mm.cm.fn) + " faces, " + std::to_string(r.ribsRight) + " right and " +
          std::to_string(r.ribsLeft) + " left ribs, " + std::to_string(r.dropped) + " pieces left out, " + std::to_string(r.landmarks.size()) + " landmarks; " +
          fmt(r.seconds, 3) + " s");
  auto& res = ctx.results();
  res.set("faces", mm.cm.fn);
  res.set("vertices", mm.cm.vn);
  res.set("ribs_right", r.ribsRight);
  res.set("ribs_left", r.ribsLeft);
  res.set("pieces_left_out", r.dropped);
  res.set("landmarks", r.landmarks.size());
  res.set("seconds", r.seconds);
}

void FilterPatientPlugin::initImportCt(RichParameterList& par) {
  par.addParam(RichString("path", "", "Path (file or folder)",
                          "A segmentation file (.stl .obj .ply .off .nii .nii.gz) or a folder of them; may be relative."));
  par.addParam(RichString("labelTable", "", "Label table",
                          "Names of a NIfTI map's labels if the file has none: '1 rib_left_1; 2 ...', JSON, or a file path."));
  addInt(par, "minVoxels", 1, "Minimum voxels",
         "NIfTI only: labels with fewer voxels are skipped (Log). 1 keeps every label.", pectus::patient::kMinVoxelsRange);
}

void FilterPatientPlugin::runImportCt(FilterContext& ctx) {
  pectus::patient::ImportOptions opt;
  opt.labelTable = ctx.string("labelTable").toStdString();
  opt.minVoxels = ctx.intIn("minVoxels");
  const std::string path = ctx.string("path").trimmed().toStdString();
  const auto t0 = std::chrono::steady_clock::now();
  pectus::patient::ImportReport report;
  auto prog = [&](int pc, const char* w) { ctx.progress(pc, w); };
  auto structures = pectus::patient::importSegmentation(path, opt, &report, prog);  // before any layer is added
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  long long faces = 0, vertices = 0;
  for (std::size_t i = 0; i < structures.size(); ++i) {
    auto& s = structures[i];
    MeshModel& mm = ctx.addLayer(QString::fromStdString(s.name), i == 0);  // the first one becomes current
    vcg::tri::Append<CMeshO, CMeshO>::MeshCopy(mm.cm, *s.mesh);
    vcg::tri::UpdateNormal<CMeshO>::PerVertexNormalizedPerFaceNormalized(mm.cm);
    vcg::tri::UpdateBounding<CMeshO>::Box(mm.cm);
    faces += mm.cm.fn, vertices += mm.cm.vn;
  }
  ctx.log("Imported " + std::to_string(structures.size()) + (structures.size() == 1 ? " structure" : " structures") +
          " from " + path + ": " + std::to_string(faces) + " faces, " + std::to_string(vertices) +
          " vertices in all; frame and units as in the files; " + fmt(secs, 3) + " s");
  for (const auto& l : report.lines) ctx.log(l);
  ctx.results().set("structures", structures.size());
  ctx.results().set("faces", faces);
  ctx.results().set("vertices", vertices);
  ctx.results().set("seconds", secs);
}
