// fdem/output.hpp: files of a run folder, each written atomically (temp file + rename), so an interrupted
// run never leaves a half-written file.
//   VTU: VTK XML UnstructuredGrid with appended raw binary data (header_type UInt64), read by ParaView and numpy.
//   PVD: the collection of snapshots with their times.
//   JSON: a minimal writer for summary.json.
#pragma once

#include <cmath>
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
    std::vector<std::string> component_names;  // optional: ComponentName_i attributes (ParaView's labels)
};

// A string array of the file's FieldData (one value per entry: e.g. the region names, indexed by region id).
struct VtuStrings {
    std::string name;
    std::vector<std::string> values;
};

// Triangles (3 node indices each) with point coordinates xy (2 per point); z is written as 0.
// Optional line cells (2 node indices each) follow the triangles. field_data: string arrays in FieldData (ASCII,
// VTK's encoding of a string array: each character's code, each string ended by 0). time (s, finite): written as the
// FieldData array TimeValue, the dataset's time for ParaView (NaN: none).
std::string vtu_document(const std::vector<double>& xy, const std::vector<int>& triangles, const std::vector<int>& lines,
                         const std::vector<VtuArray>& point_data, const std::vector<VtuArray>& cell_data,
                         const std::vector<VtuStrings>& field_data = {}, double time = std::nan(""));

// Points alone, each a VTK_VERTEX cell, with their data (the contact records of a snapshot).
std::string points_vtu_document(const std::vector<double>& xy, const std::vector<VtuArray>& point_data,
                                const std::vector<VtuStrings>& field_data = {}, double time = std::nan(""));

// The FieldData block of a VTU file (also used by mesh/vtu.cpp's ASCII writer): "" when there is nothing.
std::string vtu_field_data(const std::vector<VtuStrings>& field_data, double time = std::nan(""));

// Stress measures of a triangle from its in-plane Cauchy stress (sxx, syy, sxy) and the out-of-plane szz (0 in
// plane stress): principal stresses s1 >= s2 (Mohr's circle: (sxx + syy)/2 +- sqrt(((sxx - syy)/2)^2 + sxy^2)) and
// the von Mises stress sqrt(((s_xx - s_yy)^2 + (s_yy - s_zz)^2 + (s_zz - s_xx)^2) / 2 + 3 s_xy^2), all in Pa.
struct StressMeasures {
    double s1, s2, von_mises;
};
StressMeasures stress_measures(double sxx, double syy, double sxy, double szz);

// A fresh run into an existing folder: removes the previous run's snapshots (snapshots/step_*.vtu, contacts_*.vtu and their
// .tmp files) and run.pvd, so that the folder never mixes two runs' snapshots. Other files are left alone.
// Returns the number of files removed.
int remove_previous_snapshots(const std::string& out_dir);

std::string pvd_document(const std::vector<std::pair<double, std::string>>& snapshots);
// The contact file beside a snapshot: snapshots/step_N.vtu -> snapshots/contacts_N.vtu (points at the loaded contact
// faces; contacts.pvd lists them as run.pvd lists the snapshots).
std::string contact_snapshot_name(const std::string& snapshot);

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
    // A number that is written with a decimal point or an exponent even when whole (1.0, not 1): a TOML float
    // stays a float for the reader (fdem check --json's case tree).
    static Json real(double v) { Json j(v); j.real_ = true; return j; }
    static Json object() { Json j; j.kind_ = Object; return j; }
    static Json array() { Json j; j.kind_ = Array; return j; }
    Json& operator[](const std::string& key);  // object member (created if absent)
    void push_back(Json v);                     // array element
    std::string dump(int indent = 2) const;

private:
    enum Kind { Null, Bool, Number, String, Array, Object } kind_ = Null;
    double num_ = 0;
    bool real_ = false;
    std::string str_;
    std::vector<std::pair<std::string, Json>> members_;  // objects
    std::vector<Json> items_;                            // arrays
    void dump_to(std::string& out, int indent, int depth) const;
};

// Number formatting used by every text output: shortest form that reads back to the same double.
std::string format_double(double v);

}  // namespace fdem
