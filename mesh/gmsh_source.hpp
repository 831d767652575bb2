// mesh/gmsh_source.hpp: meshes made or read through Gmsh's C++ API (no external gmsh program).
#pragma once

#include <string>

#include "mesh/mesh.hpp"

namespace fdem::mesh {

// RAII guard around gmsh::initialize/finalize; Gmsh's model is global state, so one at a time.
class GmshSession {
public:
    explicit GmshSession(bool verbose = false);
    ~GmshSession();
    GmshSession(const GmshSession&) = delete;
    GmshSession& operator=(const GmshSession&) = delete;
};

// Throws MeshError("<what>: <first Gmsh error>") if Gmsh logged an error in the current session.
void throw_on_gmsh_error(const std::string& what);

// Converts the 2D mesh of the current Gmsh model (already generated) into a Mesh: 3-node triangles only,
// nodes renumbered compactly, every triangle made counter-clockwise, physical groups copied by name.
// Throws MeshError if the model holds no triangles or a triangle has (near) zero area.
Mesh extract_current_model();

// A rectangle [x0, x0+width] x [y0, y0+height] meshed with unstructured triangles of size `size` (m).
// Physical groups: "body" (surface), "bottom", "right", "top", "left" (edges), and the corners
// "corner_bl", "corner_br", "corner_tr", "corner_tl" (points).
Mesh mesh_rectangle(double x0, double y0, double width, double height, double size);

// Runs a Gmsh .geo script through the API and meshes it in 2D; `size_factor` scales Gmsh's
// Mesh.MeshSizeFactor (1 keeps the script's sizes). Throws MeshError naming the file on failure.
Mesh mesh_geo_file(const std::string& path, double size_factor = 1.0);

// Reads a Gmsh .msh file (formats 2.2 and 4.1) with its physical groups.
Mesh read_msh_file(const std::string& path);

}  // namespace fdem::mesh
