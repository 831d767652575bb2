// mesh/vtu.hpp: the mesh as a VTK UnstructuredGrid (.vtu, ASCII XML) for `fdem mesh` and ParaView.
#pragma once

#include <string>

#include "mesh/topology.hpp"

namespace fdem::mesh {

// One .vtu with the split mesh's points and two kinds of cells in a single UnstructuredGrid:
//   the triangles (VTK_TRIANGLE), then one line (VTK_LINE) per classified edge (side A's node copies).
// Cell data (Int32): "cell_kind" with the codes of the run's snapshots: 0 triangle, 1 cohesive element (a
// crackable or bonded edge), 2 dry joint, 3 other edge (interior, free boundary; not in snapshots); "region",
// "body", "contact_capable" (triangles; -1 on edges); "edge_class" (edges: 0 interior, 1 crackable, 2 bonded,
// 3 dry, 4 free_boundary; -1 on triangles). FieldData: region_names, cell_kind_names, edge_class_names (string
// arrays indexed by those ids).
// Point data (Int32): "node_origin" (node of the shared-node mesh). In ParaView, Threshold on cell_kind
// separates the two. Written to path + ".tmp" and renamed, so a reader never sees a half-written file.
// Throws MeshError naming the path if it cannot be written.
void write_topology_vtu(const std::string& path, const Topology& topo);

}  // namespace fdem::mesh
