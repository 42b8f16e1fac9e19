#include "pectus/fe/io.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string_view>
#include <unordered_map>

#include "pectus/errors.h"

namespace pectus::fe {

namespace {
std::ofstream openOut(const std::string& path) {
  std::ofstream f(path);
  if (!f) throw IOError("Cannot write " + path + " (check the folder exists and is writable).");
  f.precision(12);
  return f;
}
const char* tissueSetName(int t) {
  switch (t) {
    case 1: return "BONE";
    case 2: return "CARTILAGE";
    case 3: return "STERNUM";
    default: return nullptr;
  }
}
std::string setName(int t) {
  const char* n = tissueSetName(t);
  return n ? std::string(n) : "TISSUE" + std::to_string(t);
}
// Text written through a buffer that goes to the file in 1 MB pieces; numbers by std::to_chars with 12
// significant digits (the same text as the stream's precision(12)), without the stream's
// per-number locale and virtual calls (the rib cage's 360k-tet .vtu: 2.5 s through the stream).
class TextOut {
 public:
  explicit TextOut(std::ofstream& f) : f_(f) { buf_.reserve(kFlush + 64); }
  TextOut(const TextOut&) = delete;
  TextOut& operator=(const TextOut&) = delete;
  ~TextOut() { flush(); }
  TextOut& operator<<(const char* s) { buf_ += s; return check(); }
  TextOut& operator<<(const std::string& s) { buf_ += s; return check(); }
  TextOut& operator<<(char c) { buf_ += c; return check(); }
  TextOut& operator<<(std::size_t v) {
    char b[24];
    buf_.append(b, std::to_chars(b, b + sizeof b, v).ptr);
    return check();
  }
  TextOut& operator<<(int v) {
    char b[16];
    buf_.append(b, std::to_chars(b, b + sizeof b, v).ptr);
    return check();
  }
  TextOut& operator<<(double v) {
    char b[32];
    buf_.append(b, std::to_chars(b, b + sizeof b, v, std::chars_format::general, 12).ptr);
    return check();
  }
  void flush() {
    f_.write(buf_.data(), static_cast<std::streamsize>(buf_.size()));
    buf_.clear();
  }

 private:
  static constexpr std::size_t kFlush = std::size_t(1) << 20;
  TextOut& check() {
    if (buf_.size() >= kFlush) flush();
    return *this;
  }
  std::ofstream& f_;
  std::string buf_;
};
}  // namespace

void writeVtu(const std::string& path, const TetMesh& m, const Result* res) {
  if (res && res->u.size() != 3 * m.numNodes()) throw InputError("writeVtu: the result does not belong to this mesh.");
  std::ofstream file = openOut(path);
  TextOut f(file);
  const int nen = m.nodesPerTet();
  f << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
    << "<UnstructuredGrid>\n<Piece NumberOfPoints=\"" << m.numNodes() << "\" NumberOfCells=\"" << m.numTets() << "\">\n";
  f << "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const auto& p : m.nodes) f << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  f << "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">\n";
  for (const auto& e : m.tets) {
    for (int a = 0; a < nen; ++a) f << e[a] << (a + 1 < nen ? ' ' : '\n');
  }
  f << "</DataArray>\n<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">\n";
  for (int t = 0; t < m.numTets(); ++t) f << (t + 1) * nen << '\n';
  f << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (int t = 0; t < m.numTets(); ++t) f << (m.order == 2 ? 24 : 10) << '\n';
  f << "</DataArray>\n</Cells>\n<CellData Scalars=\"tissue\">\n<DataArray type=\"Int32\" Name=\"tissue\" format=\"ascii\">\n";
  for (int t : m.tissue) f << t << '\n';
  f << "</DataArray>\n";
  if (res) {
    f << "<DataArray type=\"Float64\" Name=\"von_mises\" format=\"ascii\">\n";
    for (double v : res->vonMises) f << v << '\n';
    f << "</DataArray>\n<DataArray type=\"Float64\" Name=\"equivalent_strain\" format=\"ascii\">\n";
    for (double v : res->eqStrain) f << v << '\n';
    f << "</DataArray>\n";
  }
  f << "</CellData>\n";
  if (res) {
    f << "<PointData Vectors=\"displacement\">\n<DataArray type=\"Float64\" Name=\"displacement\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    for (int i = 0; i < m.numNodes(); ++i) f << res->u(3 * i) << ' ' << res->u(3 * i + 1) << ' ' << res->u(3 * i + 2) << '\n';
    f << "</DataArray>\n<DataArray type=\"Float64\" Name=\"von_mises_nodal\" format=\"ascii\">\n";
    for (double v : averageToNodes(m, res->vonMises)) f << v << '\n';
    f << "</DataArray>\n<DataArray type=\"Float64\" Name=\"equivalent_strain_nodal\" format=\"ascii\">\n";
    for (double v : averageToNodes(m, res->eqStrain)) f << v << '\n';
    f << "</DataArray>\n</PointData>\n";
  }
  f << "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
  f.flush();
  if (!file) throw IOError("Writing " + path + " failed (disk full?).");
}

void writeCalculixInp(const std::string& path, const Problem& p, const InpOptions& opt) {
  if (!p.mesh) throw InputError("writeCalculixInp: no mesh.");
  const TetMesh& m = *p.mesh;
  std::ofstream file = openOut(path);
  TextOut f(file);
  f << "*HEADING\n" << opt.heading << "\n** units: mm, N, MPa. Written by pectus_fe (pectus-meshlab).\n*NODE, NSET=NALL\n";
  for (int i = 0; i < m.numNodes(); ++i)
    f << i + 1 << ", " << m.nodes[i].x() << ", " << m.nodes[i].y() << ", " << m.nodes[i].z() << '\n';
  const int nen = m.nodesPerTet();
  std::set<int> tissues(m.tissue.begin(), m.tissue.end());
  for (int tis : tissues) {
    f << "*ELEMENT, TYPE=" << (m.order == 2 ? "C3D10" : "C3D4") << ", ELSET=E" << setName(tis) << '\n';
    for (int t = 0; t < m.numTets(); ++t) {
      if (m.tissue[t] != tis) continue;
      f << t + 1;
      // C3D10 lines hold at most 16 entries: 1 + 10 fits
      for (int a = 0; a < nen; ++a) f << ", " << m.tets[t][a] + 1;
      f << '\n';
    }
  }
  for (int tis : tissues) {
    auto it = p.materials.find(tis);
    if (it == p.materials.end()) throw InputError("writeCalculixInp: no material for tissue " + std::to_string(tis) + ".");
    const Material& mt = it->second;
    f << "*MATERIAL, NAME=" << setName(tis) << '\n';
    if (opt.nlgeom && mt.model != MaterialModel::StVenantKirchhoff) {
      // CalculiX's NEO HOOKE: W = C10 (I1bar - 3) + (J - 1)^2 / D1 with the same small-strain E and nu
      // (C10 = mu / 2, D1 = 2 / K). It is MaterialModel::NeoHookeanDecoupled; the ln J form has no ccx
      // equivalent, and this is the nearest (same shear term, another volumetric one).
      const double mu = mt.E / (2 * (1 + mt.nu)), K = mt.E / (3 * (1 - 2 * mt.nu));
      if (mt.model == MaterialModel::NeoHookean)
        f << "** " << setName(tis) << ": pectus_fe's neo-Hookean W = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2 written as "
             "CalculiX's NEO HOOKE (other volumetric term)\n";
      f << "*HYPERELASTIC, NEO HOOKE\n" << mu / 2 << ", " << 2 / K << '\n';
    } else {
      // a small-strain step solves Hooke's law for every model (their common limit)
      f << "*ELASTIC\n" << mt.E << ", " << mt.nu << '\n';
    }
    f << "*SOLID SECTION, ELSET=E" << setName(tis) << ", MATERIAL=" << setName(tis) << '\n';
  }
  if (!opt.printNodes.empty()) {
    f << "*NSET, NSET=OUT\n";
    for (size_t k = 0; k < opt.printNodes.size(); ++k) f << opt.printNodes[k] + 1 << ((k % 8 == 7 || k + 1 == opt.printNodes.size()) ? "\n" : ", ");
  }
  f << "*BOUNDARY\n";
  for (const auto& d : p.fixed) f << d.node + 1 << ", " << d.dof + 1 << ", " << d.dof + 1 << ", " << d.value << '\n';
  if (opt.nlgeom)
    f << "*STEP, NLGEOM, INC=" << std::max(100, 4 * opt.increments) << "\n*STATIC, DIRECT\n" << 1.0 / std::max(1, opt.increments) << ", 1.0\n";
  else
    f << "*STEP\n*STATIC\n";
  bool any = false;
  for (size_t i = 0; i < p.force.size(); ++i)
    for (int d = 0; d < 3; ++d)
      if (p.force[i](d) != 0) {
        if (!any) f << "*CLOAD\n", any = true;
        f << i + 1 << ", " << d + 1 << ", " << p.force[i](d) << '\n';
      }
  if (!opt.printNodes.empty()) f << "*NODE PRINT, NSET=OUT\nU\n";
  f << "*NODE FILE\nU\n*EL FILE\nS, E\n*END STEP\n";
  f.flush();
  if (!file) throw IOError("Writing " + path + " failed (disk full?).");
}

namespace {
std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}
std::string_view trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string_view::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}
// the comma-separated fields of a line, trimmed, as views into it (a trailing comma: an empty last field)
void splitCommas(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    out.push_back(trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
}
// "KEY=VALUE" parameters of a keyword line (upper case), plus the keyword itself under ""
std::map<std::string, std::string> keywordLine(std::string_view line) {
  std::map<std::string, std::string> kv;
  std::vector<std::string_view> parts;
  splitCommas(line, parts);
  kv[""] = upper(std::string(parts[0]));
  for (std::size_t i = 1; i < parts.size(); ++i) {
    const auto eq = parts[i].find('=');
    if (eq == std::string_view::npos) kv[upper(std::string(parts[i]))] = "";
    else kv[upper(std::string(trim(parts[i].substr(0, eq))))] = upper(std::string(trim(parts[i].substr(eq + 1))));
  }
  return kv;
}
}  // namespace

std::unique_ptr<InpModel> readCalculixInp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw IOError("Cannot read " + path + ".");
  std::ostringstream all;
  all << f.rdbuf();
  return parseCalculixInp(all.str(), path);
}

namespace {
// Reads a deck in two passes over what it holds: line by line, keywords open blocks and data lines fill
// them (in the deck's ids); then the mesh and the problem are assembled from the blocks (ids -> indices).
class InpReader {
 public:
  InpReader(const std::string& text, const std::string& path) : text_(text), path_(path) {}

  std::unique_ptr<InpModel> read() {
    for (std::size_t pos = 0; pos < text_.size();) {
      std::size_t end = text_.find('\n', pos);
      if (end == std::string::npos) end = text_.size();
      const std::string_view line = trim(std::string_view(text_).substr(pos, end - pos));
      pos = end + 1;
      ++lineNo_;
      if (line.empty() || line.rfind("**", 0) == 0) continue;
      if (line[0] == '*')
        keyword(line);
      else if (block_ != "*HEADING")
        dataLine(line);
    }
    assemble();
    return std::move(owned_);
  }

 private:
  struct BoundaryLine { int node, first, last; double value; };  // deck node id, dofs first..last (1-based)

  [[noreturn]] void fail(const std::string& why) const {
    throw IOError(path_ + ", line " + std::to_string(lineNo_) + ": " + why);
  }
  double number(std::string_view t) const {
    double v = 0;
    const char* first = t.data() + (!t.empty() && t[0] == '+' ? 1 : 0);
    const auto r = std::from_chars(first, t.data() + t.size(), v);
    if (t.empty() || r.ec != std::errc() || r.ptr != t.data() + t.size() || !std::isfinite(v))
      fail("'" + std::string(t) + "' is not a finite number");
    return v;
  }
  int integer(std::string_view t) const {
    int i = 0;
    const auto r = std::from_chars(t.data(), t.data() + t.size(), i);
    if (!t.empty() && r.ec == std::errc() && r.ptr == t.data() + t.size()) return i;
    const double v = number(t);  // 1.0, 1e3, +1, or an error
    // the range first: casting a double outside long's range (e.g. 1e300) is undefined behaviour
    if (!(std::abs(v) <= 2e9) || v != std::floor(v)) fail("'" + std::string(t) + "' is not an integer");
    return static_cast<int>(v);
  }
  // the 0-based node of a deck node id
  int node(int id) const {
    const auto it = nodeIndex_.find(id);
    if (it == nodeIndex_.end()) throw IOError(path_ + ": node " + std::to_string(id) + " is used but not defined.");
    return it->second;
  }

  // A keyword line: opens its block and reads its parameters.
  void keyword(std::string_view line) {
    const auto kv = keywordLine(line);
    const std::string& key = kv.at("");
    block_ = key;
    InpOptions& options = owned_->options;
    if (key == "*HEADING" || key == "*NODE FILE" || key == "*EL FILE" || key == "*END STEP" || key == "*BOUNDARY" ||
        key == "*CLOAD" || key == "*NODE") {
      // no parameters to read: the block's data lines carry it
    } else if (key == "*STATIC") {
      options.increments = 1;
    } else if (key == "*NODE PRINT") {
      const auto it = kv.find("NSET");
      if (it != kv.end() && nsets_.count(it->second))
        for (int id : nsets_[it->second]) options.printNodes.push_back(id);
    } else if (key == "*ELEMENT") {
      const auto type = kv.find("TYPE"), set = kv.find("ELSET");
      if (type == kv.end() || (type->second != "C3D4" && type->second != "C3D10")) fail("only *ELEMENT, TYPE=C3D4 or C3D10 is read");
      const int n = type->second == "C3D10" ? 10 : 4;
      if (nen_ && n != nen_) fail("C3D4 and C3D10 elements in one deck");
      nen_ = n;
      currentSet_ = set == kv.end() ? std::string("EALL") : set->second;
      if (!tissueOfSet_.count(currentSet_)) {
        int label = static_cast<int>(tissueOfSet_.size()) + 4;
        for (int t = 1; t <= 3; ++t)
          if (currentSet_ == "E" + setName(t)) label = t;
        tissueOfSet_[currentSet_] = label;
      }
      currentTissue_ = tissueOfSet_[currentSet_];
    } else if (key == "*MATERIAL") {
      const auto it = kv.find("NAME");
      if (it == kv.end()) fail("*MATERIAL without NAME");
      currentMaterial_ = it->second;
    } else if (key == "*ELASTIC") {
      const auto it = kv.find("TYPE");
      if (it != kv.end() && it->second != "ISO") fail("only isotropic *ELASTIC is read");
      if (currentMaterial_.empty()) fail("*ELASTIC outside a *MATERIAL");
    } else if (key == "*HYPERELASTIC") {
      if (!kv.count("NEO HOOKE")) fail("only *HYPERELASTIC, NEO HOOKE is read");
      if (currentMaterial_.empty()) fail("*HYPERELASTIC outside a *MATERIAL");
    } else if (key == "*SOLID SECTION") {
      const auto set = kv.find("ELSET"), mat = kv.find("MATERIAL");
      if (set == kv.end() || mat == kv.end()) fail("*SOLID SECTION needs ELSET and MATERIAL");
      if (!tissueOfSet_.count(set->second)) fail("*SOLID SECTION of an unknown ELSET " + set->second);
      if (!materials_.count(mat->second)) fail("*SOLID SECTION with an undefined MATERIAL " + mat->second);
      owned_->problem.materials[tissueOfSet_[set->second]] = materials_[mat->second];
    } else if (key == "*NSET") {
      const auto it = kv.find("NSET");
      if (it == kv.end()) fail("*NSET without a name");
      currentSet_ = it->second;
      nsets_[currentSet_];
    } else if (key == "*STEP") {
      options.nlgeom = kv.count("NLGEOM") > 0;
    } else {
      fail("keyword " + key + " is not read by pectus_fe (it reads the decks it writes)");
    }
  }

  // A data line of the open block.
  void dataLine(std::string_view line) {
    splitCommas(line, t_);
    const auto& t = t_;
    if (block_ == "*NODE") {
      if (t.size() < 4) fail("a node line needs an id and three coordinates");
      const int id = integer(t[0]);
      TetMesh& m = owned_->mesh;
      if (nodeIndex_.empty()) nodeIndex_.reserve(std::max<std::size_t>(1024, text_.size() / 64));
      if (!nodeIndex_.emplace(id, m.numNodes()).second) fail("node " + std::string(t[0]) + " defined twice");
      m.nodes.emplace_back(number(t[1]), number(t[2]), number(t[3]));
    } else if (block_ == "*ELEMENT") {
      if (static_cast<int>(t.size()) != nen_ + 1) fail("an element line needs an id and " + std::to_string(nen_) + " nodes");
      std::array<int, 10> e{};
      for (int a = 0; a < nen_; ++a) e[a] = integer(t[a + 1]);
      elems_.emplace_back(integer(t[0]), e);
      elemTissue_.push_back(currentTissue_);
    } else if (block_ == "*ELASTIC") {
      if (t.size() < 2) fail("*ELASTIC needs E and the Poisson ratio");
      materials_[currentMaterial_] = {number(t[0]), number(t[1])};
    } else if (block_ == "*HYPERELASTIC") {
      // C10, D1 -> mu = 2 C10, K = 2 / D1 -> E, nu (the same small-strain limit)
      if (t.size() < 2) fail("*HYPERELASTIC, NEO HOOKE needs C10 and D1");
      const double c10 = number(t[0]), d1 = number(t[1]);
      if (!(c10 > 0 && d1 > 0)) fail("*HYPERELASTIC, NEO HOOKE needs C10 > 0 and D1 > 0 (pectus_fe models compressible tissue)");
      const double mu = 2 * c10, K = 2 / d1;
      materials_[currentMaterial_] = {9 * K * mu / (3 * K + mu), (3 * K - 2 * mu) / (2 * (3 * K + mu)), MaterialModel::NeoHookeanDecoupled};
    } else if (block_ == "*NSET") {
      for (std::string_view id : t)
        if (!id.empty()) nsets_[currentSet_].push_back(integer(id));
    } else if (block_ == "*BOUNDARY") {
      if (t.size() < 2) fail("a *BOUNDARY line needs a node and a dof");
      const int first = integer(t[1]), last = t.size() > 2 && !t[2].empty() ? integer(t[2]) : first;
      boundary_.push_back({integer(t[0]), first, last, t.size() > 3 ? number(t[3]) : 0.0});
    } else if (block_ == "*CLOAD") {
      if (t.size() < 3) fail("a *CLOAD line needs a node, a dof and a value");
      const int dof = integer(t[1]);
      if (dof < 1 || dof > 3) fail("*CLOAD dof must be 1, 2 or 3");
      std::array<double, 3> fv{0, 0, 0};
      fv[std::size_t(dof - 1)] = number(t[2]);
      loads_.emplace_back(integer(t[0]), fv);
    } else if (block_ == "*STEP") {
      fail("text after *STEP: a procedure keyword (*STATIC) was expected");
    } else if (block_ == "*STATIC") {
      InpOptions& options = owned_->options;
      if (options.nlgeom && !t.empty()) {
        const double inc = number(t[0]);
        if (!(inc > 0 && inc <= 1)) fail("*STATIC initial increment must be in (0, 1]");
        options.increments = std::max(1, static_cast<int>(std::lround(1.0 / inc)));
      }
    }  // data lines of *NODE PRINT / *NODE FILE / *EL FILE (output variables) are not needed here
  }

  // The tets in element id order (the writer's ids are the tets' 1-based indices), the supports and the
  // loads on 0-based nodes.
  void assemble() {
    TetMesh& m = owned_->mesh;
    Problem& p = owned_->problem;
    if (elems_.empty()) throw IOError(path_ + ": no *ELEMENT of type C3D4 or C3D10.");
    std::vector<std::size_t> order(elems_.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return elems_[a].first < elems_[b].first; });
    for (std::size_t k = 1; k < order.size(); ++k)
      if (elems_[order[k]].first == elems_[order[k - 1]].first)
        throw IOError(path_ + ": element " + std::to_string(elems_[order[k]].first) + " is defined twice.");
    m.order = nen_ == 10 ? 2 : 1;
    for (std::size_t k : order) {
      std::array<int, 10> e{};
      for (int a = 0; a < nen_; ++a) e[a] = node(elems_[k].second[a]);
      m.tets.push_back(e);
      m.tissue.push_back(elemTissue_[k]);
    }
    for (const auto& b : boundary_) {
      if (b.first < 1 || b.last > 3 || b.first > b.last) throw IOError(path_ + ": *BOUNDARY dofs must be within 1..3.");
      for (int d = b.first; d <= b.last; ++d) p.fixed.push_back({node(b.node), d - 1, b.value});
    }
    p.force.assign(m.nodes.size(), Eigen::Vector3d::Zero());
    for (const auto& l : loads_) p.force[std::size_t(node(l.first))] += Eigen::Vector3d(l.second[0], l.second[1], l.second[2]);
    for (int& id : owned_->options.printNodes) id = node(id);
    p.mesh = &owned_->mesh;
  }

  const std::string& text_;
  const std::string& path_;
  std::unique_ptr<InpModel> owned_ = std::make_unique<InpModel>();
  std::unordered_map<int, int> nodeIndex_;                     // deck node id -> 0-based node
  std::vector<std::pair<int, std::array<int, 10>>> elems_;     // (deck element id, deck node ids)
  std::vector<int> elemTissue_;
  std::map<std::string, int> tissueOfSet_;                     // ELSET name -> tissue label
  std::map<std::string, Material> materials_;
  std::map<std::string, std::vector<int>> nsets_;
  std::vector<std::pair<int, std::array<double, 3>>> loads_;  // (deck node id, force)
  std::vector<BoundaryLine> boundary_;
  std::string block_, currentSet_, currentMaterial_;
  int nen_ = 0, lineNo_ = 0, currentTissue_ = 0;
  std::vector<std::string_view> t_;  // the current data line's fields
};
}  // namespace

std::unique_ptr<InpModel> parseCalculixInp(const std::string& text, const std::string& path) {
  return InpReader(text, path).read();
}

}  // namespace pectus::fe
