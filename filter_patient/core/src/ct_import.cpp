// Import of a CT segmentation: mesh files (own STL and OBJ readers, vcglib's PLY and OFF importers) and
// NIfTI label maps (label_volume.h), one file or a folder of them. See ct_import.h.
#include "pectus/patient/ct_import.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <optional>
#include <regex>
#include <set>
#include <sstream>

#include <vcg/complex/algorithms/update/bounding.h>
#include <wrap/io_trimesh/import_off.h>
#include <wrap/io_trimesh/import_ply.h>

#include "pectus/patient/label_volume.h"
#include "pectus/surface_cmesh.h"
#include "pectus/errors.h"
#include "pectus/union_find.h"
#include "pectus/format.h"

namespace fs = std::filesystem;

namespace pectus::patient {
namespace {

// ------------------------------------------------------------------------------------------------
// small helpers

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

std::string trim(const std::string& s) {
  std::size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}

std::string fileName(const std::string& path) { return fs::path(path).filename().string(); }

/// "1,234,567"
std::string grouped(long long n) {
  std::string d = std::to_string(n < 0 ? -n : n), out;
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (i && (d.size() - i) % 3 == 0) out += ',';
    out += d[i];
  }
  return n < 0 ? "-" + out : out;
}

std::string fixed(double v, int decimals = 1) { return fixedText(v, decimals); }

std::string plural(long long n, const char* one, const char* many) {
  return grouped(n) + " " + (n == 1 ? one : many);
}

enum class Kind { Stl, Obj, Ply, Off, Nifti, Unknown };

Kind kindOf(const std::string& path) {
  const std::string n = lower(fileName(path));
  auto ends = [&](const char* e) {
    const std::size_t l = std::strlen(e);
    return n.size() > l && n.compare(n.size() - l, l, e) == 0;
  };
  if (ends(".stl")) return Kind::Stl;
  if (ends(".obj")) return Kind::Obj;
  if (ends(".ply")) return Kind::Ply;
  if (ends(".off")) return Kind::Off;
  if (ends(".nii") || ends(".nii.gz")) return Kind::Nifti;
  return Kind::Unknown;
}

const char* kKnown = "STL, OBJ, PLY, OFF (.stl .obj .ply .off) or NIfTI (.nii .nii.gz)";

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IOError("cannot open file '" + path + "'");
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw IOError("cannot read file '" + path + "'");
  return s.str();
}

/// a number in C locale (MeshLab's process may run under a locale with decimal commas)
bool parseFloat(const std::string& tok, double& v) {
  const char* b = tok.data();
  const char* e = b + tok.size();
  if (b != e && *b == '+') ++b;
  const auto r = std::from_chars(b, e, v);
  return r.ec == std::errc() && r.ptr == e;
}

bool parseInt(const std::string& tok, long long& v) {
  const char* b = tok.data();
  const char* e = b + tok.size();
  if (b != e && *b == '+') ++b;
  const auto r = std::from_chars(b, e, v);
  return r.ec == std::errc() && r.ptr == e;
}

std::vector<std::string> tokens(const std::string& line) {
  std::vector<std::string> t;
  std::istringstream s(line);
  std::string w;
  while (s >> w) t.push_back(w);
  return t;
}

/// lines without '\r', the last one also without a trailing newline
std::vector<std::string> splitLines(const std::string& text) {
  std::vector<std::string> out;
  std::size_t a = 0;
  while (a <= text.size()) {
    std::size_t b = text.find('\n', a);
    if (b == std::string::npos) b = text.size();
    std::string l = text.substr(a, b - a);
    if (!l.empty() && l.back() == '\r') l.pop_back();
    out.push_back(std::move(l));
    a = b + 1;
  }
  if (!out.empty() && out.back().empty()) out.pop_back();
  return out;
}

// ------------------------------------------------------------------------------------------------
// a triangle soup as a file gives it, then one finishing step for every format

using Soup = pectus::Surface;

void finish(const std::string& path, Soup& s, CMeshO& out, MeshFileStats& st) {
  st.trianglesRead = int(s.F.size());
  // faces with a non-finite corner are dropped (they would poison every later computation)
  std::vector<char> finite(s.V.size());
  for (std::size_t i = 0; i < s.V.size(); ++i)
    finite[i] = std::isfinite(s.V[i][0]) && std::isfinite(s.V[i][1]) && std::isfinite(s.V[i][2]);
  std::vector<std::array<int, 3>> faces;
  faces.reserve(s.F.size());
  for (const auto& f : s.F) {
    if (finite[std::size_t(f[0])] && finite[std::size_t(f[1])] && finite[std::size_t(f[2])])
      faces.push_back(f);
    else
      ++st.nonFiniteFaces;
  }
  if (faces.empty())
    throw TopologyError("file '" + path + "' has no faces" +
                     (st.nonFiniteFaces ? " with finite coordinates (" + grouped(st.nonFiniteFaces) +
                                              " faces with NaN or infinite coordinates)"
                                        : std::string()));
  // merge vertices at the same position (as vcg's RemoveDuplicateVertex: equal in the mesh's float
  // scalar), keeping the first one's order; vertices no face uses are not carried over
  std::map<std::array<Scalarm, 3>, int> at;
  std::vector<int> map(s.V.size(), -1);
  std::vector<Point3m> pos;
  std::vector<char> used(s.V.size(), 0);
  for (const auto& f : faces)
    for (int k : f) used[std::size_t(k)] = 1;
  int referenced = 0;
  for (std::size_t i = 0; i < s.V.size(); ++i) {
    if (!used[i]) continue;
    ++referenced;
    const std::array<Scalarm, 3> key{Scalarm(s.V[i][0]), Scalarm(s.V[i][1]), Scalarm(s.V[i][2])};
    auto it = at.find(key);
    if (it == at.end()) {
      it = at.emplace(key, int(pos.size())).first;
      pos.emplace_back(key[0], key[1], key[2]);
    }
    map[i] = it->second;
  }
  st.unreferencedVertices = int(s.V.size()) - referenced;
  st.mergedVertices = referenced - int(pos.size());

  out.Clear();
  auto vi = vcg::tri::Allocator<CMeshO>::AddVertices(out, pos.size());
  for (std::size_t i = 0; i < pos.size(); ++i, ++vi) vi->P() = pos[i];
  auto fi = vcg::tri::Allocator<CMeshO>::AddFaces(out, faces.size());
  for (const auto& f : faces) {
    for (int k = 0; k < 3; ++k) fi->V(k) = &out.vert[std::size_t(map[std::size_t(f[std::size_t(k)])])];
    ++fi;
  }
  vcg::tri::UpdateBounding<CMeshO>::Box(out);
}

// ------------------------------------------------------------------------------------------------
// STL: binary when the size is 84 + 50 n for the count n in the header (a binary header may itself
// start with "solid"), else ASCII when it starts with "solid"

std::uint32_t le32(const char* p) {
  const auto* u = reinterpret_cast<const unsigned char*>(p);
  return std::uint32_t(u[0]) | std::uint32_t(u[1]) << 8 | std::uint32_t(u[2]) << 16 | std::uint32_t(u[3]) << 24;
}
float leFloat(const char* p) {
  const std::uint32_t u = le32(p);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

void readStl(const std::string& path, Soup& s, MeshFileStats& st) {
  const std::string data = readAll(path);
  const bool binarySize = data.size() >= 84 && std::uint64_t(data.size()) == 84 + 50 * std::uint64_t(le32(&data[80]));
  std::size_t first = 0;
  while (first < data.size() && std::isspace(static_cast<unsigned char>(data[first]))) ++first;
  const bool solid = lower(data.substr(first, 5)) == "solid";
  if (binarySize) {
    st.format = "binary STL";
    const std::uint32_t n = le32(&data[80]);
    s.V.reserve(std::size_t(n) * 3);
    s.F.reserve(n);
    for (std::uint32_t i = 0; i < n; ++i) {
      const char* p = &data[84 + 50 * std::size_t(i) + 12];  // after the normal
      for (int k = 0; k < 3; ++k)
        s.V.push_back({double(leFloat(p + 12 * k)), double(leFloat(p + 12 * k + 4)), double(leFloat(p + 12 * k + 8))});
      const int b = int(3 * i);
      s.F.push_back({b, b + 1, b + 2});
    }
    return;
  }
  if (!solid) {
    if (data.size() >= 84)
      throw IOError("file '" + path + "' is not an STL file: it does not start with 'solid' (ASCII) and its size, " +
                       grouped((long long)data.size()) + " bytes, is not 84 + 50 x " + grouped(le32(&data[80])) +
                       " triangles (binary); the file is truncated or not STL");
    throw IOError("file '" + path + "' is not an STL file (" + grouped((long long)data.size()) +
                     " bytes, neither 'solid ...' text nor a binary STL)");
  }
  st.format = "ASCII STL";
  const auto lines = splitLines(data);
  std::vector<int> corners;  // vertex indices of the facet being read
  bool inFacet = false, ended = false;
  for (std::size_t ln = 0; ln < lines.size(); ++ln) {
    const auto t = tokens(lines[ln]);
    if (t.empty()) continue;
    const std::string k = lower(t[0]);
    auto where = [&] { return "file '" + path + "' line " + std::to_string(ln + 1) + ": "; };
    if (k == "facet") {
      if (inFacet) throw IOError(where() + "'facet' before the previous facet's 'endfacet'");
      inFacet = true;
      corners.clear();
    } else if (k == "vertex") {
      if (!inFacet) throw IOError(where() + "'vertex' outside a facet");
      std::array<double, 3> p{};
      if (t.size() < 4 || !parseFloat(t[1], p[0]) || !parseFloat(t[2], p[1]) || !parseFloat(t[3], p[2]))
        throw IOError(where() + "a vertex needs three numbers: '" + trim(lines[ln]) + "'");
      corners.push_back(int(s.V.size()));
      s.V.push_back({p[0], p[1], p[2]});
    } else if (k == "endfacet") {
      if (!inFacet) throw IOError(where() + "'endfacet' without 'facet'");
      if (corners.size() < 3)
        throw IOError(where() + "a facet with " + std::to_string(corners.size()) + " vertices (3 needed)");
      for (std::size_t c = 1; c + 1 < corners.size(); ++c) s.F.push_back({corners[0], corners[c], corners[c + 1]});
      inFacet = false;
    } else if (k == "endsolid") {
      if (inFacet) throw IOError(where() + "'endsolid' inside a facet");
      ended = true;
    } else if (k == "solid") {
      ended = false;  // files with several solids
    } else if (k == "outer" || k == "endloop") {
      // structure only
    } else {
      throw IOError(where() + "unexpected '" + t[0] + "' in an ASCII STL file");
    }
  }
  if (inFacet || !ended)
    throw IOError("file '" + path + "' ends " + (inFacet ? "inside a facet" : "without 'endsolid'") +
                     ": the file is truncated");
}

// ------------------------------------------------------------------------------------------------
// OBJ (own reader: MeshLab 2020.09's importer aborts on some exports)

void readObj(const std::string& path, Soup& s, MeshFileStats& st) {
  st.format = "OBJ";
  const auto lines = splitLines(readAll(path));
  struct Pending {
    long long index;
    std::size_t line;
  };
  std::vector<std::array<long long, 3>> faces;  // 1-based absolute indices, checked at the end
  std::vector<std::size_t> faceLine;
  for (std::size_t ln = 0; ln < lines.size(); ++ln) {
    std::string line = lines[ln];
    const std::size_t first = ln;
    while (!line.empty() && line.back() == '\\' && ln + 1 < lines.size()) {  // continuation
      line.pop_back();
      line += " " + lines[++ln];
    }
    const auto t = tokens(line);
    if (t.empty() || t[0][0] == '#') continue;
    auto where = [&] { return "file '" + path + "' line " + std::to_string(first + 1) + ": "; };
    if (t[0] == "v") {
      std::array<double, 3> p{};
      if (t.size() < 4 || !parseFloat(t[1], p[0]) || !parseFloat(t[2], p[1]) || !parseFloat(t[3], p[2]))
        throw IOError(where() + "a vertex needs three numbers: '" + trim(line) + "'");
      s.V.push_back({p[0], p[1], p[2]});  // a 4th value (w) or colours after x y z are ignored
    } else if (t[0] == "f" || t[0] == "fo") {
      if (t.size() < 4)
        throw IOError(where() + "a face needs at least 3 vertices: '" + trim(line) + "'");
      std::vector<long long> idx;
      for (std::size_t i = 1; i < t.size(); ++i) {
        const std::string v = t[i].substr(0, t[i].find('/'));  // i, i/t, i//n, i/t/n
        long long k = 0;
        if (!parseInt(v, k) || k == 0)
          throw IOError(where() + "bad vertex index '" + t[i] + "' (indices start at 1; negative ones count back)");
        if (k < 0) {
          k += (long long)(s.V.size()) + 1;  // relative to the vertices read so far
          if (k < 1)
            throw IOError(where() + "vertex index " + v + " refers before the first vertex (" +
                             std::to_string(s.V.size()) + " vertices defined before this line)");
        }
        idx.push_back(k);
      }
      for (std::size_t c = 1; c + 1 < idx.size(); ++c) {  // polygons: a fan from the first corner
        faces.push_back({idx[0], idx[c], idx[c + 1]});
        faceLine.push_back(first + 1);
      }
    }
    // vt, vn, vp, o, g, s, usemtl, mtllib, l, p and the rest: not part of the surface
  }
  for (std::size_t i = 0; i < faces.size(); ++i) {
    std::array<int, 3> f{};
    for (int k = 0; k < 3; ++k) {
      const long long v = faces[i][std::size_t(k)];
      if (v > (long long)(s.V.size()))
        throw IOError("file '" + path + "' line " + std::to_string(faceLine[i]) + ": face refers to vertex " +
                         std::to_string(v) + " but the file has " + std::to_string(s.V.size()) + " vertices");
      f[std::size_t(k)] = int(v - 1);
    }
    s.F.push_back(f);
  }
}

// ------------------------------------------------------------------------------------------------
// PLY and OFF through vcglib's importers


void readPly(const std::string& path, Soup& s, MeshFileStats& st) {
  st.format = "PLY";
  OwnedMesh m;
  int mask = 0;
  const int err = vcg::tri::io::ImporterPLY<CMeshO>::Open(m, path.c_str(), mask);
  if (vcg::tri::io::ImporterPLY<CMeshO>::ErrorCritical(err))
    throw IOError("file '" + path + "' cannot be read as PLY: " + vcg::tri::io::ImporterPLY<CMeshO>::ErrorMsg(err));
  s = surfaceOf(m);
}

void readOff(const std::string& path, Soup& s, MeshFileStats& st) {
  st.format = "OFF";
  OwnedMesh m;
  int mask = 0;
  const int err = vcg::tri::io::ImporterOFF<CMeshO>::Open(m, path.c_str(), mask);
  if (err != 0)
    throw IOError("file '" + path + "' cannot be read as OFF: " + vcg::tri::io::ImporterOFF<CMeshO>::ErrorMsg(err));
  s = surfaceOf(m);
}

// ------------------------------------------------------------------------------------------------
// label tables

using LabelTable = std::map<int, std::string>;

// label v (0: the background, left out) named `name`; a value out of range, a label without a name or named
// twice is refused, naming the source and where in it
void addLabel(LabelTable& out, const std::string& source, long long v, const std::string& name, const std::string& where) {
  if (v == 0) return;  // background
  if (v < INT32_MIN || v > INT32_MAX) throw InputError(source + where + ": label value out of range");
  if (name.empty()) throw InputError(source + where + ": label " + std::to_string(v) + " has no name");
  const auto r = out.emplace(int(v), name);
  if (!r.second && r.first->second != name)
    throw InputError(source + where + ": label " + std::to_string(v) + " is named twice ('" + r.first->second +
                     "' and '" + name + "')");
}

// a flat JSON object: {"name": value} or {"value": "name"}
LabelTable parseJsonTable(const std::string& t, const std::string& source) {
  LabelTable out;
  static const std::regex pair(R"re("((?:[^"\\]|\\.)*)"\s*:\s*(?:"((?:[^"\\]|\\.)*)"|(-?\d+)))re");
  for (auto it = std::sregex_iterator(t.begin(), t.end(), pair); it != std::sregex_iterator(); ++it) {
    const auto& m = *it;
    long long v = 0;
    if (m[3].matched) {  // {"name": value}
      parseInt(m[3].str(), v);
      addLabel(out, source, v, m[1].str(), "");
    } else if (parseInt(trim(m[1].str()), v)) {  // {"value": "name"}
      addLabel(out, source, v, m[2].str(), "");
    } else {
      throw InputError(source + ": JSON key '" + m[1].str() + "' is not a label value (write {\"1\": \"name\"})");
    }
  }
  if (out.empty()) throw InputError(source + ": no label in the JSON object (write {\"1\": \"name\", ...})");
  return out;
}

// the table's entries: its lines, each split at its semicolons too when `semicolons`
std::vector<std::string> tableEntries(const std::string& text, bool semicolons) {
  std::vector<std::string> entries;
  for (const auto& l : splitLines(text)) {
    if (!semicolons) {
      entries.push_back(l);
      continue;
    }
    std::size_t a = 0;
    while (true) {
      const std::size_t b = l.find(';', a);
      entries.push_back(l.substr(a, b == std::string::npos ? std::string::npos : b - a));
      if (b == std::string::npos) break;
      a = b + 1;
    }
  }
  return entries;
}

// the fields of an entry, separated by blanks, commas, semicolons, '=' or ':'
std::vector<std::string> entryFields(const std::string& rest) {
  std::vector<std::string> f;
  std::string cur;
  for (char c : rest) {
    if (std::isspace(static_cast<unsigned char>(c)) || c == ',' || c == ';' || c == '=' || c == ':' || c == '\t') {
      if (!cur.empty()) f.push_back(cur), cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) f.push_back(cur);
  return f;
}

// entries of 'value name' (Slicer: value name R G B A; ITK-SNAP: IDX R G B A VIS MSH "name"; CSV: 1,"name");
// comments (#) and blank entries are skipped, and a header before the first label
LabelTable parseTableEntries(const std::vector<std::string>& entries, const std::string& source, bool semicolons) {
  LabelTable out;
  bool firstData = true;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const std::string e = trim(entries[i]);
    if (e.empty() || e[0] == '#') continue;
    const std::string where = semicolons && entries.size() > 1 ? " entry '" + e + "'" : " line " + std::to_string(i + 1);
    std::string name;
    std::string rest = e;
    const std::size_t q = e.find('"');
    if (q != std::string::npos) {  // ITK-SNAP: IDX R G B A VIS MSH "name"; CSV: 1,"name"
      const std::size_t q2 = e.find('"', q + 1);
      if (q2 == std::string::npos) throw InputError(source + where + ": unclosed quote");
      name = e.substr(q + 1, q2 - q - 1);
      rest = e.substr(0, q);
    }
    const std::vector<std::string> f = entryFields(rest);
    long long v = 0;
    if (f.empty() || !parseInt(f[0], v)) {
      if (firstData) {  // a header such as "value,name"
        firstData = false;
        continue;
      }
      throw InputError(source + where + ": '" + e + "' does not start with a label value (write 'value name')");
    }
    firstData = false;
    if (name.empty()) {
      if (f.size() < 2) throw InputError(source + where + ": label " + f[0] + " has no name (write 'value name')");
      name = f[1];  // Slicer colour tables: value name R G B A
    }
    addLabel(out, source, v, name, where);
  }
  return out;
}

std::map<int, std::string> parseTableText(const std::string& text, const std::string& source, bool semicolons) {
  const std::string t = trim(text);
  if (!t.empty() && t[0] == '{') return parseJsonTable(t, source);
  return parseTableEntries(tableEntries(text, semicolons), source, semicolons);
}

std::optional<std::string> sidecarOf(const std::string& niftiPath) {
  const fs::path p(niftiPath);
  const fs::path dir = p.parent_path();
  const std::string stem = structureName(niftiPath);
  for (const char* suffix : {"", "_labels"})
    for (const char* ext : {".txt", ".csv", ".json"}) {
      const fs::path c = dir / (stem + suffix + ext);
      std::error_code ec;
      if (fs::is_regular_file(c, ec)) return c.string();
    }
  return std::nullopt;
}

std::string bboxText(const CMeshO& m) {
  const auto d = m.bbox.Dim();
  return fixed(d[0]) + " x " + fixed(d[1]) + " x " + fixed(d[2]);
}

std::string valueList(const std::vector<int>& v, std::size_t maxShown = 20) {
  std::string s;
  for (std::size_t i = 0; i < v.size() && i < maxShown; ++i) s += (i ? ", " : "") + std::to_string(v[i]);
  if (v.size() > maxShown) s += ", ... (" + std::to_string(v.size()) + " in all)";
  return s;
}

// ------------------------------------------------------------------------------------------------
// NIfTI files: one Structure per label (label map) or one for the file (mask)

void importNifti(const std::string& path, const ImportOptions& opt, std::vector<Structure>& out,
                 std::vector<std::string>& lines, std::set<std::string>& usedSidecars,
                 const std::function<void(int, const char*)>& labelProgress) {
  const LabelVolume v = readNifti(path);
  std::map<int, std::size_t> voxels;
  for (const std::int32_t l : v.labels)
    if (l != 0) ++voxels[l];
  const auto sp = v.spacing();
  const std::string spacing = fixed(sp[0], 3) + " x " + fixed(sp[1], 3) + " x " + fixed(sp[2], 3) + " mm";
  const std::string file = fileName(path);

  std::map<int, std::string> table;
  std::string tableSource;
  const auto sidecar = sidecarOf(path);
  if (!v.names.empty()) {
    table = v.names, tableSource = "the file's own label table";
    // readNifti may have taken the names from this sidecar: it is not listed as skipped
    if (sidecar) usedSidecars.insert(fs::path(*sidecar).lexically_normal().string());
  } else if (!trim(opt.labelTable).empty()) {
    table = parseLabelTable(opt.labelTable), tableSource = "parameter 'Label table'";
  } else if (sidecar) {
    table = parseLabelTable(*sidecar), tableSource = fileName(*sidecar);
    usedSidecars.insert(fs::path(*sidecar).lexically_normal().string());
  }
  const bool labelMap = voxels.size() > 1 || !v.names.empty() || sidecar.has_value();

  if (voxels.empty()) {
    lines.push_back(file + ": no labelled voxel (all 0), skipped");
    return;
  }
  auto add = [&](int label, const std::string& name, std::size_t n) {
    if ((long long)n < opt.minVoxels) {
      lines.push_back(name + " (" + file + (labelMap ? " label " + std::to_string(label) : std::string()) + "): " +
                      plural((long long)n, "voxel", "voxels") + ", fewer than " + std::to_string(opt.minVoxels) +
                      ", skipped");
      return;
    }
    Structure s;
    s.name = name;
    s.source = path;
    s.label = labelMap ? label : 0;
    extractLabelSurface(v, label, *s.mesh);
    vcg::tri::UpdateBounding<CMeshO>::Box(*s.mesh);
    lines.push_back(describe(s) + "; " + plural((long long)n, "voxel", "voxels") + ", spacing " + spacing + ", size " +
                    bboxText(*s.mesh) + " mm");
    out.push_back(std::move(s));
  };
  if (!labelMap) {  // a mask: the file names the structure
    add(voxels.begin()->first, structureName(path), voxels.begin()->second);
    return;
  }
  if (table.empty())
    throw InputError("label map " + path + " has " + std::to_string(voxels.size()) +
                     " labels but no label table: give one in parameter 'Label table' (lines 'value name')");
  std::vector<int> missing;
  for (const auto& [l, n] : voxels)
    if (!table.count(l)) missing.push_back(l);
  if (!missing.empty())
    throw InputError("label map " + path + ": label value" + (missing.size() > 1 ? "s " : " ") + valueList(missing) +
                     (missing.size() > 1 ? " are" : " is") + " in the image but not in the label table (" +
                     tableSource + "): add a line 'value name' for each");
  int done = 0;
  for (const auto& [l, n] : voxels) {
    if (labelProgress) labelProgress(int(100 * done++ / int(voxels.size())), table[l].c_str());
    add(l, table[l], n);
  }
}

}  // namespace

// ------------------------------------------------------------------------------------------------

std::string structureName(const std::string& path) {
  std::string n = fs::path(path).filename().string();
  const std::string l = lower(n);
  for (const char* e : {".nii.gz", ".nii", ".stl", ".obj", ".ply", ".off"}) {
    const std::size_t k = std::strlen(e);
    if (l.size() > k && l.compare(l.size() - k, k, e) == 0) return n.substr(0, n.size() - k);
  }
  return n;
}

std::map<int, std::string> parseLabelTable(const std::string& textOrPath) {
  const std::string t = trim(textOrPath);
  std::error_code ec;
  if (!t.empty() && t.find('\n') == std::string::npos && t[0] != '{' && fs::is_regular_file(t, ec))
    return parseTableText(readAll(t), "label table " + t, false);
  return parseTableText(textOrPath, "label table", true);
}

int countComponents(const CMeshO& m) {
  UnionFind sets(m.vert.size());
  std::vector<char> used(m.vert.size(), 0);
  for (const auto& f : m.face) {
    if (f.IsD()) continue;
    const int a = sets.find(int(vcg::tri::Index(m, f.cV(0))));
    for (int k = 0; k < 3; ++k) {
      const int vi = int(vcg::tri::Index(m, f.cV(k)));
      used[std::size_t(vi)] = 1;
      sets.unite(vi, a);
    }
  }
  int n = 0;
  for (std::size_t i = 0; i < sets.size(); ++i)
    if (used[i] && sets.isRoot(int(i))) ++n;
  return n;
}

std::string describe(const Structure& s) {
  const CMeshO& m = *s.mesh;
  return s.name + ": " + plural(m.fn, "face", "faces") + ", " + plural(m.vn, "vertex", "vertices") + ", " +
         plural(countComponents(m), "component", "components") + ", from " + fileName(s.source) +
         (s.label ? " label " + std::to_string(s.label) : std::string());
}

void readMeshFile(const std::string& path, CMeshO& out, MeshFileStats& stats) {
  stats = MeshFileStats{};
  out.Clear();
  std::error_code ec;
  if (!fs::exists(path, ec)) throw IOError("file '" + path + "' does not exist");
  if (!fs::is_regular_file(path, ec)) throw IOError("'" + path + "' is not a file");
  Soup s;
  switch (kindOf(path)) {
    case Kind::Stl: readStl(path, s, stats); break;
    case Kind::Obj: readObj(path, s, stats); break;
    case Kind::Ply: readPly(path, s, stats); break;
    case Kind::Off: readOff(path, s, stats); break;
    case Kind::Nifti:
      throw IOError("file '" + path + "' is a NIfTI label map, not a mesh: import it with 'Pectus: Import CT Segmentation'");
    case Kind::Unknown:
      throw IOError("file '" + path + "' has an unknown extension '" + fs::path(path).extension().string() +
                       "': give " + kKnown);
  }
  finish(path, s, out, stats);
}

void readMeshFile(const std::string& path, CMeshO& out) {
  MeshFileStats st;
  readMeshFile(path, out, st);
}

namespace {

// the options and the path: a minimum voxel count in range, a path that exists
void checkImportInput(const std::string& path, const ImportOptions& opt) {
  if (opt.minVoxels < kMinVoxelsRange.lo)
    throw InputError("minimum voxel count must be >= " + std::to_string(int(kMinVoxelsRange.lo)) + ", got " +
                     std::to_string(opt.minVoxels));
  std::error_code ec;
  if (trim(path).empty()) throw InputError("no path given: give a segmentation file or a folder of them");
  if (!fs::exists(path, ec)) throw IOError("'" + path + "' does not exist: give a segmentation file or a folder of them");
}

// the files to import: the file at path, or the folder's files of a known kind (sorted); the folder's
// other entries in `other`
std::vector<std::string> segmentationFiles(const std::string& path, std::vector<std::string>& other) {
  std::vector<std::string> files;
  std::error_code ec;
  const bool folder = fs::is_directory(path, ec);
  if (!folder) {
    if (kindOf(path) == Kind::Unknown)
      throw IOError("file '" + path + "' has an unknown extension '" + fs::path(path).extension().string() +
                       "': give " + kKnown + ", or a folder of them");
    files.push_back(path);
    return files;
  }
  for (const auto& e : fs::directory_iterator(path, ec)) {
    const std::string n = e.path().filename().string();
    std::error_code ec2;
    if (e.is_regular_file(ec2) && kindOf(n) != Kind::Unknown)
      files.push_back(e.path().string());
    else
      other.push_back(n + (e.is_directory(ec2) ? "/" : ""));
  }
  if (ec) throw IOError("cannot list folder '" + path + "': " + ec.message());
  std::sort(files.begin(), files.end());
  std::sort(other.begin(), other.end());
  if (files.empty()) {
    std::string found;
    for (std::size_t i = 0; i < other.size() && i < 10; ++i) found += (i ? ", " : "") + other[i];
    if (other.size() > 10) found += ", ... (" + std::to_string(other.size()) + " in all)";
    throw IOError("folder '" + path + "' has no " + kKnown + " file; found " +
                     (other.empty() ? std::string("nothing") : found));
  }
  return files;
}

// a mesh file as one structure, described in `lines`
Structure meshStructure(const std::string& f, std::vector<std::string>& lines) {
  Structure s;
  s.name = structureName(f);
  s.source = f;
  MeshFileStats st;
  readMeshFile(f, *s.mesh, st);
  std::string line = describe(s) + "; " + st.format + ", size " + bboxText(*s.mesh) + " (file units)";
  if (st.nonFiniteFaces)
    line += "; " + plural(st.nonFiniteFaces, "face", "faces") + " with NaN or infinite coordinates dropped";
  lines.push_back(line);
  return s;
}

// the folder's other entries that no label map took as its label table, in a line of `lines`
void reportSkipped(const std::string& path, const std::vector<std::string>& other, const std::set<std::string>& usedSidecars,
                   std::vector<std::string>& lines) {
  std::vector<std::string> skipped;
  for (const auto& o : other)
    if (!usedSidecars.count((fs::path(path) / o).lexically_normal().string())) skipped.push_back(o);
  if (!skipped.empty()) {
    std::string l = "skipped " + plural((long long)skipped.size(), "file", "files") + " (not " + kKnown + "): ";
    for (std::size_t i = 0; i < skipped.size() && i < 20; ++i) l += (i ? ", " : "") + skipped[i];
    if (skipped.size() > 20) l += ", ...";
    lines.push_back(l);
  }
}

}  // namespace

std::vector<Structure> importSegmentation(const std::string& path, const ImportOptions& opt, ImportReport* report,
                                          const std::function<void(int, const char*)>& progress) {
  checkImportInput(path, opt);
  std::vector<std::string> other;
  const std::vector<std::string> files = segmentationFiles(path, other);

  std::vector<Structure> out;
  std::vector<std::string> lines;
  std::set<std::string> usedSidecars;
  for (std::size_t i = 0; i < files.size(); ++i) {
    const std::string& f = files[i];
    const std::string name = fileName(f);
    const int base = int(100 * i / files.size()), span = int(100 * (i + 1) / files.size()) - base;
    if (progress) progress(base, name.c_str());
    if (kindOf(f) == Kind::Nifti) {
      importNifti(f, opt, out, lines, usedSidecars, [&](int pc, const char*) {
        if (progress) progress(base + span * pc / 100, name.c_str());
      });
      continue;
    }
    out.push_back(meshStructure(f, lines));
  }
  if (progress) progress(100, "done");

  reportSkipped(path, other, usedSidecars, lines);
  if (out.empty()) {
    std::string why;
    for (const auto& l : lines) why += (why.empty() ? "" : "; ") + l;
    throw InputError("nothing to import from '" + path + "': " + why);
  }
  if (report) report->lines.insert(report->lines.end(), lines.begin(), lines.end());
  return out;
}

}  // namespace pectus::patient
