#include "pectus/patient/label_volume.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>

#include <nifti2_io.h>
#include <vcg/complex/allocate.h>

#include "pectus/errors.h"
#include "marching_cubes.h"

namespace pectus::patient {

namespace fs = std::filesystem;

Eigen::Vector3d LabelVolume::spacing() const {
  return {voxelToMm.block<3, 1>(0, 0).norm(), voxelToMm.block<3, 1>(0, 1).norm(), voxelToMm.block<3, 1>(0, 2).norm()};
}

std::vector<int> LabelVolume::presentLabels() const {
  std::vector<int> out;
  // labels are usually few and clustered: a sorted small set beats a hash set here
  std::vector<std::int32_t> seen;
  std::int32_t last = 0;
  for (std::int32_t v : labels) {
    if (v == 0 || v == last) continue;
    last = v;
    auto it = std::lower_bound(seen.begin(), seen.end(), v);
    if (it == seen.end() || *it != v) seen.insert(it, v);
  }
  out.assign(seen.begin(), seen.end());
  return out;
}

// ------------------------------------------------------------------------------------------------
// label tables

namespace {

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return {};
  const auto b = s.find_last_not_of(" \t\r\n");
  return s.substr(a, b - a + 1);
}

std::string xmlUnescape(const std::string& s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '&') { out += s[i]; continue; }
    static const std::array<std::pair<const char*, char>, 5> ents{
        {{"&amp;", '&'}, {"&lt;", '<'}, {"&gt;", '>'}, {"&quot;", '"'}, {"&apos;", '\''}}};
    bool done = false;
    for (const auto& [e, c] : ents)
      if (s.compare(i, std::strlen(e), e) == 0) {
        out += c;
        i += std::strlen(e) - 1;
        done = true;
        break;
      }
    if (!done) out += s[i];
  }
  return out;
}

std::string xmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

bool parseInt(const std::string& s, int& v) {
  const std::string t = trim(s);
  if (t.empty()) return false;
  char* end = nullptr;
  const long x = std::strtol(t.c_str(), &end, 10);
  if (end == t.c_str() || *end != 0 || x < std::numeric_limits<int>::min() || x > std::numeric_limits<int>::max()) return false;
  v = int(x);
  return true;
}

// <Label Key="1" ...><![CDATA[name]]></Label> or <Label Key="1" ...>name</Label> (Caret/GIFTI label table)
std::map<int, std::string> parseXmlLabels(const std::string& xml) {
  std::map<int, std::string> names;
  std::size_t pos = 0;
  while ((pos = xml.find("<Label", pos)) != std::string::npos) {
    const std::size_t tagEnd = xml.find('>', pos);
    if (tagEnd == std::string::npos) break;
    const char after = xml[pos + 6];
    if (after != ' ' && after != '\t' && after != '\n' && after != '\r') { pos = tagEnd; continue; }  // <LabelTable>
    const std::string tag = xml.substr(pos, tagEnd - pos);
    pos = tagEnd + 1;
    const std::size_t k = tag.find("Key=");
    if (k == std::string::npos || k + 5 > tag.size()) continue;
    const char q = tag[k + 4];
    if (q != '"' && q != '\'') continue;
    const std::size_t kEnd = tag.find(q, k + 5);
    int key;
    if (kEnd == std::string::npos || !parseInt(tag.substr(k + 5, kEnd - k - 5), key)) continue;
    if (!tag.empty() && tag.back() == '/') continue;  // <Label .../>: no name
    const std::size_t close = xml.find("</Label>", pos);
    if (close == std::string::npos) break;
    std::string body = trim(xml.substr(pos, close - pos));
    pos = close + 8;
    if (body.rfind("<![CDATA[", 0) == 0) {
      const std::size_t e = body.find("]]>");
      body = body.substr(9, e == std::string::npos ? std::string::npos : e - 9);
    } else {
      body = xmlUnescape(body);
    }
    body = trim(body);
    if (!body.empty()) names[key] = body;
  }
  return names;
}

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// "name.nii.gz" -> "name", "name.nii" -> "name"
std::string niftiStem(const std::string& path) {
  const std::string l = lower(path);
  for (const char* ext : {".nii.gz", ".nii"})
    if (l.size() > std::strlen(ext) && l.compare(l.size() - std::strlen(ext), std::string::npos, ext) == 0)
      return path.substr(0, path.size() - std::strlen(ext));
  return path;
}

bool isGz(const std::string& path) {
  const std::string l = lower(path);
  return l.size() > 3 && l.compare(l.size() - 3, 3, ".gz") == 0;
}

}  // namespace

std::map<int, std::string> readLabelTable(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IOError("label table '" + path + "' cannot be opened: check the path");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  std::map<int, std::string> names;
  const std::string t = trim(text);
  if (t.find("<Label") != std::string::npos) {
    names = parseXmlLabels(t);
  } else if (!t.empty() && t.front() == '{') {
    // JSON object {"1": "rib_left_1", ...} (flat; values are strings)
    std::size_t pos = 1;
    auto readString = [&](std::string& s) {
      while (pos < t.size() && std::isspace(static_cast<unsigned char>(t[pos]))) ++pos;
      if (pos >= t.size() || t[pos] != '"') return false;
      ++pos;
      s.clear();
      while (pos < t.size() && t[pos] != '"') {
        if (t[pos] == '\\' && pos + 1 < t.size()) ++pos;
        s += t[pos++];
      }
      if (pos >= t.size()) return false;
      ++pos;
      return true;
    };
    while (pos < t.size()) {
      std::string key, val;
      if (!readString(key)) break;
      while (pos < t.size() && (std::isspace(static_cast<unsigned char>(t[pos])) || t[pos] == ':')) ++pos;
      if (!readString(val)) break;
      int k;
      if (parseInt(key, k) && !trim(val).empty()) names[k] = trim(val);
      while (pos < t.size() && (std::isspace(static_cast<unsigned char>(t[pos])) || t[pos] == ',')) ++pos;
      if (pos < t.size() && t[pos] == '}') break;
    }
  } else {
    // one label a line: "1 rib_left_1", "1,rib_left_1", "1<TAB>rib_left_1", or ITK-SNAP's label description
    // (IDX R G B A VIS MSH "name"); '#' starts a comment; a header line without a number is skipped
    std::istringstream ls(text);
    std::string line;
    while (std::getline(ls, line)) {
      line = trim(line);
      if (line.empty() || line[0] == '#') continue;
      const std::size_t cut = line.find_first_of(",;\t ");
      if (cut == std::string::npos) continue;
      int k;
      if (!parseInt(line.substr(0, cut), k)) continue;
      std::string rest = line.substr(cut + 1);
      const std::size_t q0 = rest.find('"');
      const std::size_t q1 = q0 == std::string::npos ? q0 : rest.find('"', q0 + 1);
      if (q1 != std::string::npos) rest = rest.substr(q0 + 1, q1 - q0 - 1);
      rest = trim(rest);
      while (!rest.empty() && (rest.front() == ',' || rest.front() == ';')) rest = trim(rest.substr(1));
      if (!rest.empty()) names[k] = rest;
    }
  }
  if (names.empty())
    throw IOError("label table '" + path +
                     "' has no entries: write one label a line ('1 rib_left_1' or '1,rib_left_1') or a JSON object {\"1\": \"rib_left_1\"}");
  return names;
}

std::string labelTableSidecar(const std::string& niftiPath) {
  const std::string stem = niftiStem(niftiPath);
  for (const char* suffix : {".txt", ".csv", ".json", "_labels.txt", "_labels.csv", "_labels.json"}) {
    const std::string p = stem + suffix;
    std::error_code ec;
    if (fs::is_regular_file(p, ec)) return p;
  }
  return {};
}

// ------------------------------------------------------------------------------------------------
// NIfTI

namespace {

struct NimDeleter {
  void operator()(nifti_image* n) const { nifti_image_free(n); }
};
using NimPtr = std::unique_ptr<nifti_image, NimDeleter>;

// libnifti's messages go to stderr; ours are the InputErrors. Set once (thread-safe static init), since
// masks may be written from several threads.
void quietNifti() {
  static const bool quiet = (nifti_set_debug_level(0), true);
  (void)quiet;
}

const char* datatypeName(int dt) {
  switch (dt) {
    case DT_UINT8: return "uint8";
    case DT_INT8: return "int8";
    case DT_INT16: return "int16";
    case DT_UINT16: return "uint16";
    case DT_INT32: return "int32";
    case DT_UINT32: return "uint32";
    case DT_FLOAT32: return "float32";
    case DT_FLOAT64: return "float64";
    case DT_INT64: return "int64";
    case DT_UINT64: return "uint64";
    case DT_RGB24: return "RGB";
    case DT_COMPLEX64: return "complex64";
    default: return "unknown";
  }
}

Eigen::Matrix4d toEigen4(const nifti_dmat44& m) {
  Eigen::Matrix4d a;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) a(r, c) = m.m[r][c];
  return a;
}

nifti_dmat44 toDmat(const Eigen::Matrix4d& a) {
  nifti_dmat44 m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m.m[r][c] = a(r, c);
  return m;
}

template <class T>
void convert(const void* data, std::size_t n, double slope, double inter, const std::string& path, const std::array<int, 3>& dims,
             std::vector<std::int32_t>& out) {
  const T* p = static_cast<const T*>(data);
  const bool scaled = slope != 0 && !(slope == 1 && inter == 0);
  out.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    double v = double(p[i]);
    if (scaled) v = slope * v + inter;
    if constexpr (std::is_integral_v<T> && sizeof(T) < 4) {
      if (!scaled) { out[i] = std::int32_t(p[i]); continue; }
    }
    if (!std::isfinite(v) || v != std::floor(v) || v < double(std::numeric_limits<std::int32_t>::min()) ||
        v > double(std::numeric_limits<std::int32_t>::max())) {
      const std::size_t nxy = std::size_t(dims[0]) * std::size_t(dims[1]);
      const std::size_t k = i / nxy, j = (i % nxy) / std::size_t(dims[0]), ii = i % std::size_t(dims[0]);
      std::ostringstream s;
      s.precision(6);
      s << "'" << path << "' is not a label map: voxel (" << ii << ", " << j << ", " << k << ") holds " << v
        << "; a label map holds integer labels (export the segmentation as labels, not as probabilities or a CT image)";
      throw IOError(s.str());
    }
    out[i] = std::int32_t(v);
  }
}

}  // namespace

LabelVolume readNifti(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw IOError("NIfTI file '" + path + "' not found: check the path");
  if (fs::is_directory(path, ec)) throw IOError("'" + path + "' is a folder, not a NIfTI file");
  quietNifti();
  NimPtr nim(nifti_image_read(path.c_str(), 1));
  if (!nim || !nim->data)
    throw IOError("'" + path + "' cannot be read as NIfTI (not a .nii/.nii.gz file, truncated or damaged); export the label map as NIfTI-1 or NIfTI-2");
  const int ndim = int(nim->dim[0]);
  if (ndim < 3 || nim->nx < 1 || nim->ny < 1 || nim->nz < 1)
    throw IOError("'" + path + "' is " + std::to_string(ndim) + "-D; a label map must be a 3-D volume");
  for (int d = 4; d <= std::min(ndim, 7); ++d)
    if (nim->dim[d] > 1)
      throw IOError("'" + path + "' holds " + std::to_string(nim->dim[d]) + " volumes along dimension " + std::to_string(d) +
                       "; a label map must be one 3-D volume (export one segmentation, or one mask per structure)");
  if (nim->nx > std::numeric_limits<int>::max() || nim->ny > std::numeric_limits<int>::max() || nim->nz > std::numeric_limits<int>::max())
    throw IOError("'" + path + "' is too large");
  LabelVolume v;
  v.dims = {int(nim->nx), int(nim->ny), int(nim->nz)};
  const std::size_t n = std::size_t(nim->nx) * std::size_t(nim->ny) * std::size_t(nim->nz);
  const double slope = nim->scl_slope, inter = nim->scl_inter;
  switch (nim->datatype) {
    case DT_UINT8: convert<std::uint8_t>(nim->data, n, slope, inter, path, v.dims, v.labels); break;
    case DT_INT8: convert<std::int8_t>(nim->data, n, slope, inter, path, v.dims, v.labels); break;
    case DT_INT16: convert<std::int16_t>(nim->data, n, slope, inter, path, v.dims, v.labels); break;
    case DT_UINT16: convert<std::uint16_t>(nim->data, n, slope, inter, path, v.dims, v.labels); break;
    case DT_INT32: convert<std::int32_t>(nim->data, n, slope, inter, path, v.dims, v.labels); break;
    case DT_UINT32: convert<std::uint32_t>(nim->data, n, slope, inter, path, v.dims, v.labels); break;
    case DT_FLOAT32: convert<float>(nim->data, n, slope, inter, path, v.dims, v.labels); break;
    case DT_FLOAT64: convert<double>(nim->data, n, slope, inter, path, v.dims, v.labels); break;
    default:
      throw IOError("'" + path + "' stores " + datatypeName(nim->datatype) +
                       " voxels; a label map must be integer (uint8, int8, int16, uint16, int32, uint32) or integer-valued float32/float64");
  }

  // affine: sform, else qform, else the voxel sizes on the diagonal (no orientation known: index axes = x, y, z)
  Eigen::Matrix4d a = Eigen::Matrix4d::Identity();
  if (nim->sform_code > 0) {
    a = toEigen4(nim->sto_xyz);
  } else if (nim->qform_code > 0) {
    a = toEigen4(nim->qto_xyz);
  } else {
    for (int d = 0; d < 3; ++d) {
      const double s = nim->pixdim[d + 1];
      a(d, d) = std::isfinite(s) && s > 0 ? s : 1.0;
    }
  }
  double unit = 1.0;
  switch (XYZT_TO_SPACE(nim->xyz_units)) {
    case NIFTI_UNITS_METER: unit = 1000.0; break;
    case NIFTI_UNITS_MICRON: unit = 0.001; break;
    default: unit = 1.0;  // mm, or unknown (taken as mm)
  }
  a.topRows<3>() *= unit;
  a.row(3) << 0, 0, 0, 1;
  if (!a.allFinite() || std::abs(a.topLeftCorner<3, 3>().determinant()) < 1e-12)
    throw IOError("'" + path + "' has no usable voxel-to-world transform (its sform/qform is singular); fix the header's voxel sizes and orientation");
  v.voxelToMm = a;

  for (int e = 0; e < nim->num_ext; ++e) {
    const nifti1_extension& x = nim->ext_list[e];
    if (!x.edata || x.esize <= 8) continue;
    const std::size_t len = std::size_t(x.esize - 8);
    std::string s(x.edata, x.edata + len);
    s = s.substr(0, s.find('\0'));
    auto names = parseXmlLabels(s);
    if (!names.empty()) {
      v.names = std::move(names);
      break;
    }
  }
  if (v.names.empty()) {
    const std::string side = labelTableSidecar(path);
    if (!side.empty()) v.names = readLabelTable(side);
  }
  return v;
}

namespace {

// a NIfTI file name, a consistent volume, a folder that exists; returns the voxel count
std::size_t checkNiftiOutput(const LabelVolume& v, const std::string& path) {
  const std::string l = lower(path);
  const bool nii = l.size() > 4 && l.compare(l.size() - 4, 4, ".nii") == 0;
  const bool niigz = l.size() > 7 && l.compare(l.size() - 7, 7, ".nii.gz") == 0;
  if (!nii && !niigz) throw IOError("NIfTI output '" + path + "' must end in .nii or .nii.gz");
  const std::size_t n = std::size_t(v.dims[0]) * std::size_t(v.dims[1]) * std::size_t(v.dims[2]);
  if (v.dims[0] < 1 || v.dims[1] < 1 || v.dims[2] < 1 || v.labels.size() != n)
    throw InputError("label volume for '" + path + "' is inconsistent: dims " + std::to_string(v.dims[0]) + "x" + std::to_string(v.dims[1]) +
                     "x" + std::to_string(v.dims[2]) + " but " + std::to_string(v.labels.size()) + " labels");
  if (!v.voxelToMm.allFinite() || std::abs(v.voxelToMm.topLeftCorner<3, 3>().determinant()) < 1e-12)
    throw InputError("label volume for '" + path + "' has a singular voxel-to-mm affine");
  const fs::path parent = fs::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty() && !fs::is_directory(parent, ec))
    throw IOError("cannot write '" + path + "': folder '" + parent.string() + "' does not exist");
  return n;
}

// the voxel spacing, units, label intent and range, and both the sform and the qform of the voxel-to-mm affine
void setNiftiGeometry(const LabelVolume& v, std::int32_t lo, std::int32_t hi, nifti_image& im) {
  nifti_image* nim = &im;
  const Eigen::Vector3d sp = v.spacing();
  nim->dx = nim->pixdim[1] = sp[0];
  nim->dy = nim->pixdim[2] = sp[1];
  nim->dz = nim->pixdim[3] = sp[2];
  nim->xyz_units = NIFTI_UNITS_MM;
  nim->time_units = NIFTI_UNITS_UNKNOWN;
  nim->intent_code = NIFTI_INTENT_LABEL;
  nim->cal_min = lo;
  nim->cal_max = hi;
  const nifti_dmat44 a = toDmat(v.voxelToMm);
  nim->sform_code = NIFTI_XFORM_SCANNER_ANAT;
  nim->sto_xyz = a;
  nim->sto_ijk = nifti_dmat44_inverse(a);
  double qb, qc, qd, qx, qy, qz, dx, dy, dz, qfac;
  nifti_dmat44_to_quatern(a, &qb, &qc, &qd, &qx, &qy, &qz, &dx, &dy, &dz, &qfac);
  nim->qform_code = NIFTI_XFORM_SCANNER_ANAT;
  nim->quatern_b = qb;
  nim->quatern_c = qc;
  nim->quatern_d = qd;
  nim->qoffset_x = qx;
  nim->qoffset_y = qy;
  nim->qoffset_z = qz;
  nim->qfac = qfac;
  nim->qto_xyz = nifti_quatern_to_dmat44(qb, qc, qd, qx, qy, qz, dx, dy, dz, qfac);
  nim->qto_ijk = nifti_dmat44_inverse(nim->qto_xyz);
}

// TotalSegmentator's label table: a Caret XML extension (code 0)
std::string caretLabelTable(const std::map<int, std::string>& names) {
  static const std::array<std::array<int, 3>, 12> colors{{{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {255, 255, 0}, {255, 0, 255},
                                                          {0, 255, 255}, {255, 128, 0}, {255, 0, 128}, {128, 255, 128},
                                                          {0, 128, 255}, {128, 128, 128}, {185, 170, 155}}};
  std::ostringstream x;
  x << "<?xml version=\"1.0\" encoding=\"UTF-8\"?> <CaretExtension>  <Date><![CDATA[2013-07-14T05:45:09]]></Date>   "
       "<VolumeInformation Index=\"0\">   <LabelTable>\n";
  for (const auto& [key, name] : names) {
    const auto& c = colors[std::size_t(((key % 12) + 12) % 12)];
    x << "<Label Key=\"" << key << "\" Red=\"" << c[0] / 255.0 << "\" Green=\"" << c[1] / 255.0 << "\" Blue=\"" << c[2] / 255.0
      << "\" Alpha=\"1\">";
    if (name.find("]]>") == std::string::npos) x << "<![CDATA[" << name << "]]>";
    else x << xmlEscape(name);
    x << "</Label>\n";
  }
  x << "\n  </LabelTable>  <StudyMetaDataLinkSet>  </StudyMetaDataLinkSet>  <VolumeType><![CDATA[Label]]></VolumeType>   "
       "</VolumeInformation></CaretExtension>\n";
  return x.str();
}

}  // namespace

void writeNifti(const LabelVolume& v, const std::string& path) {
  const std::size_t n = checkNiftiOutput(v, path);
  std::error_code ec;
  std::int32_t lo = 0, hi = 0;
  for (std::int32_t x : v.labels) { lo = std::min(lo, x); hi = std::max(hi, x); }
  const bool small = lo >= std::numeric_limits<std::int16_t>::min() && hi <= std::numeric_limits<std::int16_t>::max();
  const int64_t dims[8] = {3, v.dims[0], v.dims[1], v.dims[2], 1, 1, 1, 1};
  quietNifti();
  NimPtr nim(nifti_make_new_nim(dims, small ? DT_INT16 : DT_INT32, 1));
  if (!nim || !nim->data) throw IOError("cannot write '" + path + "': out of memory");
  if (small) {
    auto* d = static_cast<std::int16_t*>(nim->data);
    for (std::size_t i = 0; i < n; ++i) d[i] = std::int16_t(v.labels[i]);
  } else {
    std::memcpy(nim->data, v.labels.data(), n * sizeof(std::int32_t));
  }
  setNiftiGeometry(v, lo, hi, *nim);
  std::snprintf(nim->descrip, sizeof(nim->descrip), "label map");
  nim->nifti_type = NIFTI_FTYPE_NIFTI1_1;
  if (nifti_set_filenames(nim.get(), path.c_str(), 0, 1) != 0) throw IOError("cannot write '" + path + "': not a valid NIfTI file name");
  nifti_set_iname_offset(nim.get(), 1);
  if (!v.names.empty()) {
    const std::string xml = caretLabelTable(v.names);
    if (nifti_add_extension(nim.get(), xml.data(), int(xml.size()), NIFTI_ECODE_IGNORE) != 0)
      throw IOError("cannot write '" + path + "': the label table does not fit in a NIfTI extension");
  }
  fs::remove(path, ec);
  nifti_image_write(nim.get());
  if (!fs::is_regular_file(path, ec) || fs::file_size(path, ec) == 0)
    throw IOError("cannot write '" + path + "': check that the folder is writable and the disk not full");
}

void extractLabelSurface(const LabelVolume& v, int label, CMeshO& out) {
  out.Clear();
  const int nx = v.dims[0], ny = v.dims[1], nz = v.dims[2];
  if (nx <= 0 || ny <= 0 || nz <= 0 || v.labels.size() != std::size_t(nx) * ny * nz) return;
  // bounding box of the label
  std::array<int, 3> lo{nx, ny, nz}, hi{-1, -1, -1};
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j) {
      const std::int32_t* row = v.labels.data() + std::size_t(nx) * (std::size_t(j) + std::size_t(ny) * std::size_t(k));
      int i0 = -1, i1 = -1;
      for (int i = 0; i < nx; ++i)
        if (row[i] == label) { if (i0 < 0) i0 = i; i1 = i; }
      if (i0 < 0) continue;
      lo = {std::min(lo[0], i0), std::min(lo[1], j), std::min(lo[2], k)};
      hi = {std::max(hi[0], i1), std::max(hi[1], j), std::max(hi[2], k)};
    }
  if (hi[0] < 0) return;
  // the mask on the box padded by one background voxel: grid point (a, b, c) = voxel (lo + (a, b, c) - 1)
  const int gx = hi[0] - lo[0] + 3, gy = hi[1] - lo[1] + 3, gz = hi[2] - lo[2] + 3;
  std::vector<std::uint8_t> mask(std::size_t(gx) * gy * gz, 0);
  auto gidx = [&](int a, int b, int c) { return std::size_t(a) + std::size_t(gx) * (std::size_t(b) + std::size_t(gy) * std::size_t(c)); };
  for (int c = 1; c + 1 < gz; ++c)
    for (int b = 1; b + 1 < gy; ++b)
      for (int a = 1; a + 1 < gx; ++a) mask[gidx(a, b, c)] = v.at(lo[0] + a - 1, lo[1] + b - 1, lo[2] + c - 1) == label;

  std::vector<Eigen::Vector3d> V;
  std::vector<std::array<int, 3>> F;
  const Eigen::Matrix4d& A = v.voxelToMm;
  marchCubes(
      gx, gy, gz, [&](int a, int b, int c) { return mask[gidx(a, b, c)] != 0; },
      [&](int a, int b, int c, int axis) {
        Eigen::Vector3d q(lo[0] + a - 1, lo[1] + b - 1, lo[2] + c - 1);
        q[axis] += 0.5;
        return Eigen::Vector3d(A.topLeftCorner<3, 3>() * q + A.block<3, 1>(0, 3));
      },
      V, [&](int, int, int, const std::array<int, 3>& f) { F.push_back(f); });
  const bool flip = A.topLeftCorner<3, 3>().determinant() < 0;
  auto vi = vcg::tri::Allocator<CMeshO>::AddVertices(out, V.size());
  for (const auto& p : V) { vi->P() = toPoint(p); ++vi; }
  auto fi = vcg::tri::Allocator<CMeshO>::AddFaces(out, F.size());
  for (const auto& f : F) {
    fi->V(0) = &out.vert[std::size_t(f[0])];
    fi->V(1) = &out.vert[std::size_t(f[flip ? 2 : 1])];
    fi->V(2) = &out.vert[std::size_t(f[flip ? 1 : 2])];
    ++fi;
  }
  vcg::tri::UpdateBounding<CMeshO>::Box(out);
}

}  // namespace pectus::patient
