// mesh/vtu.cpp: ASCII VTK XML UnstructuredGrid writer (format: VTK File Formats, "UnstructuredGrid" XML).
//
// DATA LAYOUT: cells are the n_tri triangles (ids 0..n_tri-1, same as the mesh), then the n_edges edge lines
// (ids n_tri + e, same order as Topology::edge_class).
#include "mesh/vtu.hpp"

#include <cstdio>
#include <fstream>
#include <iomanip>
#include <limits>
#include <string>
#include <vector>

namespace fdem::mesh {

namespace {
void write_ints(std::ofstream& f, const char* name, const std::vector<int>& v) {
    f << "        <DataArray type=\"Int32\" Name=\"" << name << "\" format=\"ascii\">\n";
    for (std::size_t i = 0; i < v.size(); ++i) f << (i % 16 ? " " : "          ") << v[i] << (i % 16 == 15 ? "\n" : "");
    if (v.size() % 16) f << "\n";
    f << "        </DataArray>\n";
}

// A FieldData string array in VTK's ASCII encoding: each character's code, each string ended by 0.
void write_strings(std::ofstream& f, const char* name, const std::vector<std::string>& values) {
    f << "        <DataArray type=\"String\" Name=\"" << name << "\" NumberOfTuples=\"" << values.size()
      << "\" format=\"ascii\">\n         ";
    for (const auto& v : values) {
        for (unsigned char c : v) f << " " << static_cast<int>(c);
        f << " 0";
    }
    f << "\n        </DataArray>\n";
}
}  // namespace

void write_topology_vtu(const std::string& path, const Topology& topo) {
    const Mesh& m = topo.mesh;
    const int nt = m.n_triangles(), ne = topo.n_edges(), np = m.n_nodes();
    const std::string tmp = path + ".tmp";
    {
        std::ofstream f(tmp);
        if (!f) throw MeshError("cannot write '" + tmp + "'");
        f << std::setprecision(std::numeric_limits<double>::max_digits10);
        f << "<?xml version=\"1.0\"?>\n"
          << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
          << "  <UnstructuredGrid>\n";
        // The names behind the ids (ParaView: Information panel, "Field Data").
        f << "      <FieldData>\n";
        write_strings(f, "region_names", m.regions);
        write_strings(f, "cell_kind_names", {"triangle", "cohesive element", "dry joint", "other edge"});
        std::vector<std::string> class_names;
        for (int c = 0; c < kEdgeClassCount; ++c) class_names.push_back(to_string(static_cast<EdgeClass>(c)));
        write_strings(f, "edge_class_names", class_names);
        f << "      </FieldData>\n"
          << "    <Piece NumberOfPoints=\"" << np << "\" NumberOfCells=\"" << nt + ne << "\">\n"
          << "      <Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
        for (int k = 0; k < np; ++k) f << "          " << m.xy[2 * k] << " " << m.xy[2 * k + 1] << " 0\n";
        f << "        </DataArray>\n      </Points>\n      <Cells>\n";
        std::vector<int> conn(m.tri), offsets, types, kind, region, body, capable, cls;
        for (int t = 0; t < nt; ++t) {
            offsets.push_back(3 * (t + 1));
            types.push_back(5);  // VTK_TRIANGLE
            kind.push_back(0);
            region.push_back(m.tri_region[t]);
            body.push_back(m.tri_body.empty() ? -1 : m.tri_body[t]);
            capable.push_back(0);
            cls.push_back(-1);
        }
        for (int t : topo.contact_capable) capable[t] = 1;
        for (int e = 0; e < ne; ++e) {
            // The edge's copies as seen from side A.
            const int ta = topo.edge_tri[2 * e];
            for (int end = 0; end < 2; ++end)
                for (int i = 0; i < 3; ++i)
                    if (topo.node_origin[m.tri[3 * ta + i]] == topo.edge_nodes[2 * e + end]) conn.push_back(m.tri[3 * ta + i]);
            offsets.push_back(static_cast<int>(conn.size()));
            types.push_back(3);  // VTK_LINE
            const EdgeClass ec = topo.edge_class[e];
            kind.push_back(ec == EdgeClass::crackable || ec == EdgeClass::bonded ? 1 : ec == EdgeClass::dry ? 2 : 3);
            region.push_back(-1);
            body.push_back(-1);
            capable.push_back(-1);
            cls.push_back(static_cast<int>(topo.edge_class[e]));
        }
        write_ints(f, "connectivity", conn);
        write_ints(f, "offsets", offsets);
        f << "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
        for (std::size_t i = 0; i < types.size(); ++i) f << (i % 32 ? " " : "          ") << types[i] << (i % 32 == 31 ? "\n" : "");
        if (types.size() % 32) f << "\n";
        f << "        </DataArray>\n      </Cells>\n      <CellData Scalars=\"region\">\n";
        write_ints(f, "cell_kind", kind);
        write_ints(f, "region", region);
        write_ints(f, "body", body);
        write_ints(f, "contact_capable", capable);
        write_ints(f, "edge_class", cls);
        f << "      </CellData>\n      <PointData>\n";
        write_ints(f, "node_origin", topo.node_origin);
        f << "      </PointData>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
        f.flush();
        if (!f) throw MeshError("writing '" + tmp + "' failed (disk full?)");
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        std::remove(tmp.c_str());
        throw MeshError("cannot rename '" + tmp + "' to '" + path + "'");
    }
}

}  // namespace fdem::mesh
