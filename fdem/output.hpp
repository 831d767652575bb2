// fdem/output.hpp: files of a run folder, each written atomically (temp file + rename), so an interrupted
// run never leaves a half-written file.
//   VTU: VTK XML UnstructuredGrid with appended raw binary data (header_type UInt64), read by ParaView and numpy.
//   PVD: the collection of snapshots with their times.
//   JSON: a minimal writer for summary.json.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace fdem {

// Writes `content` to `path` through `path.tmp` and a rename.
void write_file_atomic(const std::string& path, const std::string& content);

// One data array of a VTU file.
struct VtuArray {
    std::string name;
    int components = 1;
    std::vector<double> f64;   // used when !is_int
    std::vector<int32_t> i32;  // used when is_int
    bool is_int = false;
};

// Triangles (3 node indices each) with point coordinates xy (2 per point); z is written as 0.
// Optional line cells (2 node indices each) follow the triangles.
std::string vtu_document(const std::vector<double>& xy, const std::vector<int>& triangles, const std::vector<int>& lines,
                         const std::vector<VtuArray>& point_data, const std::vector<VtuArray>& cell_data);

std::string pvd_document(const std::vector<std::pair<double, std::string>>& snapshots);

// A JSON value built in code: null, bool, number, string, array or object (keys kept in insertion order).
class Json {
public:
    Json() = default;
    Json(double v) : kind_(Number), num_(v) {}
    Json(int v) : kind_(Number), num_(v) {}
    Json(long v) : kind_(Number), num_(static_cast<double>(v)) {}
    Json(long long v) : kind_(Number), num_(static_cast<double>(v)) {}
    Json(bool v) : kind_(Bool), num_(v ? 1 : 0) {}
    Json(const char* s) : kind_(String), str_(s) {}
    Json(std::string s) : kind_(String), str_(std::move(s)) {}
    static Json object() { Json j; j.kind_ = Object; return j; }
    static Json array() { Json j; j.kind_ = Array; return j; }
    Json& operator[](const std::string& key);  // object member (created if absent)
    void push_back(Json v);                     // array element
    std::string dump(int indent = 2) const;

private:
    enum Kind { Null, Bool, Number, String, Array, Object } kind_ = Null;
    double num_ = 0;
    std::string str_;
    std::vector<std::pair<std::string, Json>> members_;  // objects
    std::vector<Json> items_;                            // arrays
    void dump_to(std::string& out, int indent, int depth) const;
};

// Number formatting used by every text output: shortest form that reads back to the same double.
std::string format_double(double v);

}  // namespace fdem
