// fdem/output.cpp: atomic files, VTU/PVD documents, JSON.
#include "fdem/output.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <system_error>

namespace fdem {

void write_file_atomic(const std::string& path, const std::string& content) {
    const std::string tmp = path + ".tmp";
    {
        std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
        if (!f) throw std::runtime_error("cannot write '" + tmp + "'");
        f.write(content.data(), static_cast<std::streamsize>(content.size()));
        if (!f) throw std::runtime_error("write failed on '" + tmp + "' (disk full?)");
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) throw std::runtime_error("cannot rename '" + tmp + "' to '" + path + "': " + ec.message());
}

std::string format_double(double v) {
    if (std::isnan(v)) return "nan";
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    char buf[32];
    // %.17g always reads back exactly; try shorter forms first for readable files.
    for (int prec = 10; prec <= 17; ++prec) {
        std::snprintf(buf, sizeof buf, "%.*g", prec, v);
        if (std::strtod(buf, nullptr) == v) break;
    }
    return buf;
}

namespace {
void append_block(std::string& blob, const void* data, std::uint64_t bytes) {
    const char* h = reinterpret_cast<const char*>(&bytes);
    blob.append(h, sizeof bytes);
    blob.append(reinterpret_cast<const char*>(data), bytes);
}

void array_header(std::string& xml, const VtuArray& a, std::uint64_t offset) {
    xml += "        <DataArray type=\"";
    xml += a.is_int ? "Int32" : "Float64";
    xml += "\" Name=\"" + a.name + "\" NumberOfComponents=\"" + std::to_string(a.components) + "\"";
    for (std::size_t i = 0; i < a.component_names.size(); ++i)
        xml += " ComponentName" + std::to_string(i) + "=\"" + a.component_names[i] + "\"";
    xml += " format=\"appended\" offset=\"" + std::to_string(offset) + "\"/>\n";
}
}  // namespace

std::string vtu_field_data(const std::vector<VtuStrings>& field_data, double time) {
    if (field_data.empty() && !std::isfinite(time)) return "";
    std::string xml = "      <FieldData>\n";
    if (std::isfinite(time)) {
        // TimeValue: the snapshot's time, which ParaView and VTK's readers take as the dataset's time (one file
        // opened alone, or a series without run.pvd, then animates in seconds).
        char buf[40];
        std::snprintf(buf, sizeof buf, "%.17g", time);
        xml += "        <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">\n          ";
        xml += buf;
        xml += "\n        </DataArray>\n";
    }
    for (const auto& f : field_data) {
        xml += "        <DataArray type=\"String\" Name=\"" + f.name + "\" NumberOfTuples=\"" +
               std::to_string(f.values.size()) + "\" format=\"ascii\">\n         ";
        for (const auto& v : f.values) {
            for (unsigned char c : v) xml += " " + std::to_string(static_cast<int>(c));
            xml += " 0";
        }
        xml += "\n        </DataArray>\n";
    }
    xml += "      </FieldData>\n";
    return xml;
}

StressMeasures stress_measures(double sxx, double syy, double sxy, double szz) {
    const double c = 0.5 * (sxx + syy), r = std::hypot(0.5 * (sxx - syy), sxy);
    const double vm = std::sqrt(0.5 * ((sxx - syy) * (sxx - syy) + (syy - szz) * (syy - szz) + (szz - sxx) * (szz - sxx)) +
                                3 * sxy * sxy);
    return {c + r, c - r, vm};
}

int remove_previous_snapshots(const std::string& out_dir) {
    namespace fs = std::filesystem;
    int removed = 0;
    std::error_code ec;
    const fs::path dir(out_dir);
    for (const char* f : {"run.pvd", "run.pvd.tmp", "contacts.pvd", "contacts.pvd.tmp"})
        if (fs::remove(dir / f, ec)) ++removed;
    if (!fs::is_directory(dir / "snapshots", ec)) return removed;
    std::vector<fs::path> old;
    for (const auto& e : fs::directory_iterator(dir / "snapshots", ec)) {
        const std::string n = e.path().filename().string();
        const bool vtu = n.size() > 4 && n.compare(n.size() - 4, 4, ".vtu") == 0;
        const bool tmp = n.size() > 8 && n.compare(n.size() - 8, 8, ".vtu.tmp") == 0;
        if ((n.rfind("step_", 0) == 0 || n.rfind("contacts_", 0) == 0) && (vtu || tmp)) old.push_back(e.path());
    }
    for (const auto& p : old)
        if (fs::remove(p, ec)) ++removed;
    return removed;
}

namespace {
// An UnstructuredGrid document: points xy (2 per point, z written as 0), cells given by their connectivity, offsets
// (the end of each cell's nodes in conn) and VTK types.
std::string grid_document(const std::vector<double>& xy, const std::vector<int64_t>& conn, const std::vector<int64_t>& offs,
                          const std::vector<uint8_t>& types, const std::vector<VtuArray>& point_data,
                          const std::vector<VtuArray>& cell_data, const std::vector<VtuStrings>& field_data, double time) {
    const std::size_t np = xy.size() / 2, nc = types.size();
    std::string xml, blob;
    xml += "<?xml version=\"1.0\"?>\n";
    xml += "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n";
    xml += "  <UnstructuredGrid>\n";
    xml += vtu_field_data(field_data, time);
    xml += "    <Piece NumberOfPoints=\"" + std::to_string(np) + "\" NumberOfCells=\"" + std::to_string(nc) + "\">\n";
    auto add = [&](const VtuArray& a) {
        array_header(xml, a, blob.size());
        if (a.is_int) append_block(blob, a.i32.data(), a.i32.size() * sizeof(int32_t));
        else append_block(blob, a.f64.data(), a.f64.size() * sizeof(double));
    };
    xml += "      <PointData>\n";
    for (const auto& a : point_data) add(a);
    xml += "      </PointData>\n      <CellData>\n";
    for (const auto& a : cell_data) add(a);
    xml += "      </CellData>\n      <Points>\n";
    VtuArray pts{"Points", 3, {}, {}, false, {}};
    pts.f64.resize(3 * np);
    for (std::size_t i = 0; i < np; ++i) pts.f64[3 * i] = xy[2 * i], pts.f64[3 * i + 1] = xy[2 * i + 1], pts.f64[3 * i + 2] = 0;
    add(pts);
    xml += "      </Points>\n      <Cells>\n";
    xml += "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" offset=\"" + std::to_string(blob.size()) + "\"/>\n";
    append_block(blob, conn.data(), conn.size() * sizeof(int64_t));
    xml += "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"" + std::to_string(blob.size()) + "\"/>\n";
    append_block(blob, offs.data(), offs.size() * sizeof(int64_t));
    xml += "        <DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"" + std::to_string(blob.size()) + "\"/>\n";
    append_block(blob, types.data(), types.size());
    xml += "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n";
    xml += "  <AppendedData encoding=\"raw\">\n   _";
    xml += blob;
    xml += "\n  </AppendedData>\n</VTKFile>\n";
    return xml;
}
}  // namespace

std::string vtu_document(const std::vector<double>& xy, const std::vector<int>& triangles, const std::vector<int>& lines,
                         const std::vector<VtuArray>& point_data, const std::vector<VtuArray>& cell_data,
                         const std::vector<VtuStrings>& field_data, double time) {
    const std::size_t ntri = triangles.size() / 3, nline = lines.size() / 2;
    std::vector<int64_t> conn, offs;
    std::vector<uint8_t> types;
    conn.reserve(3 * ntri + 2 * nline);
    for (int n : triangles) conn.push_back(n);
    for (int n : lines) conn.push_back(n);
    int64_t o = 0;
    for (std::size_t c = 0; c < ntri; ++c) offs.push_back(o += 3), types.push_back(5);   // VTK_TRIANGLE
    for (std::size_t c = 0; c < nline; ++c) offs.push_back(o += 2), types.push_back(3);  // VTK_LINE
    return grid_document(xy, conn, offs, types, point_data, cell_data, field_data, time);
}

std::string points_vtu_document(const std::vector<double>& xy, const std::vector<VtuArray>& point_data,
                                const std::vector<VtuStrings>& field_data, double time) {
    const std::size_t np = xy.size() / 2;
    std::vector<int64_t> conn(np), offs(np);
    for (std::size_t i = 0; i < np; ++i) conn[i] = static_cast<int64_t>(i), offs[i] = static_cast<int64_t>(i + 1);
    const std::vector<uint8_t> types(np, 1);  // VTK_VERTEX
    return grid_document(xy, conn, offs, types, point_data, {}, field_data, time);
}

std::string contact_snapshot_name(const std::string& snapshot) {
    const std::size_t slash = snapshot.rfind('/') + 1, step = snapshot.find("step_", slash);
    if (step == std::string::npos) return snapshot;
    return snapshot.substr(0, step) + "contacts_" + snapshot.substr(step + 5);
}

std::string pvd_document(const std::vector<std::pair<double, std::string>>& snapshots) {
    std::string s = "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n";
    for (const auto& [t, file] : snapshots)
        s += "    <DataSet timestep=\"" + format_double(t) + "\" group=\"\" part=\"0\" file=\"" + file + "\"/>\n";
    s += "  </Collection>\n</VTKFile>\n";
    return s;
}

Json& Json::operator[](const std::string& key) {
    if (kind_ == Null) kind_ = Object;
    if (kind_ != Object) throw std::logic_error("Json: not an object");
    for (auto& [k, v] : members_)
        if (k == key) return v;
    members_.emplace_back(key, Json());
    return members_.back().second;
}

void Json::push_back(Json v) {
    if (kind_ == Null) kind_ = Array;
    if (kind_ != Array) throw std::logic_error("Json: not an array");
    items_.push_back(std::move(v));
}

std::string Json::dump(int indent) const {
    std::string out;
    dump_to(out, indent, 0);
    out += "\n";
    return out;
}

namespace {
void escape(std::string& out, const std::string& s) {
    out += '"';
    for (unsigned char c : s) {
        switch (c) {
            case '"': out += "\\\""; break;
            case '\\': out += "\\\\"; break;
            case '\n': out += "\\n"; break;
            case '\t': out += "\\t"; break;
            case '\r': out += "\\r"; break;
            default:
                if (c < 0x20) {
                    char b[8];
                    std::snprintf(b, sizeof b, "\\u%04x", c);
                    out += b;
                } else {
                    out += static_cast<char>(c);
                }
        }
    }
    out += '"';
}
}  // namespace

void Json::dump_to(std::string& out, int indent, int depth) const {
    const std::string pad(static_cast<std::size_t>(indent * (depth + 1)), ' '), pad0(static_cast<std::size_t>(indent * depth), ' ');
    switch (kind_) {
        case Null: out += "null"; break;
        case Bool: out += num_ != 0 ? "true" : "false"; break;
        case Number:
            if (!std::isfinite(num_)) {
                out += "null";
            } else {
                const std::string t = format_double(num_);
                out += t;
                if (real_ && t.find_first_of(".e") == std::string::npos) out += ".0";
            }
            break;
        case String: escape(out, str_); break;
        case Array:
            if (items_.empty()) { out += "[]"; break; }
            out += "[\n";
            for (std::size_t i = 0; i < items_.size(); ++i) {
                out += pad;
                items_[i].dump_to(out, indent, depth + 1);
                out += i + 1 < items_.size() ? ",\n" : "\n";
            }
            out += pad0 + "]";
            break;
        case Object:
            if (members_.empty()) { out += "{}"; break; }
            out += "{\n";
            for (std::size_t i = 0; i < members_.size(); ++i) {
                out += pad;
                escape(out, members_[i].first);
                out += ": ";
                members_[i].second.dump_to(out, indent, depth + 1);
                out += i + 1 < members_.size() ? ",\n" : "\n";
            }
            out += pad0 + "}";
            break;
    }
}

}  // namespace fdem
