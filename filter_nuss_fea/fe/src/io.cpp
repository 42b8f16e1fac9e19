#include "pectus/fe/io.h"

#include <cstdio>
#include <fstream>
#include <set>

#include "pectus/errors.h"

namespace pectus::fe {

namespace {
std::ofstream openOut(const std::string& path) {
  std::ofstream f(path);
  if (!f) throw InputError("Cannot write " + path + " (check the folder exists and is writable).");
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
}  // namespace

void writeVtu(const std::string& path, const TetMesh& m, const Result* res) {
  if (res && res->u.size() != 3 * m.numNodes()) throw InputError("writeVtu: the result does not belong to this mesh.");
  std::ofstream f = openOut(path);
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
  if (!f) throw InputError("Writing " + path + " failed (disk full?).");
}

void writeCalculixInp(const std::string& path, const Problem& p, const InpOptions& opt) {
  if (!p.mesh) throw InputError("writeCalculixInp: no mesh.");
  const TetMesh& m = *p.mesh;
  std::ofstream f = openOut(path);
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
    f << "*MATERIAL, NAME=" << setName(tis) << "\n*ELASTIC\n" << it->second.E << ", " << it->second.nu << '\n';
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
  if (!f) throw InputError("Writing " + path + " failed (disk full?).");
}

}  // namespace pectus::fe
