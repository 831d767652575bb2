// fdem/scene.cpp: see scene.hpp.
#include "fdem/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "fdem/common/errors.hpp"
#include "mesh/gmsh_source.hpp"
#include "mesh/macro.hpp"
#include "mesh/quality.hpp"
#include "mesh/wall.hpp"

namespace fdem {

mesh::Mesh make_mesh(const CaseSpec& spec) {
    const GeometrySpec& g = spec.geometry;
    mesh::Mesh m;
    try {
        if (g.type == "rectangle") m = mesh::mesh_rectangle(g.x0, g.y0, g.width, g.height, g.mesh_size);
        else if (g.type == "gmsh") m = mesh::mesh_geo_file(g.file, g.size_factor);
        else if (g.type == "msh") m = mesh::read_msh_file(g.file);
        else if (g.type == "wall") m = mesh::generate_wall(g.wall);
        else if (g.type == "macro") m = mesh::generate_macro_pier(g.macro);
        else if (g.type == "macro_wall") m = mesh::generate_macro_wall(g.macro_wall);
        else throw InputError(spec.file + ": key 'geometry.type': unsupported geometry '" + g.type + "'");
        mesh::check_quality(m, g.min_angle);
    } catch (const mesh::MeshError& e) {
        throw InputError(spec.file + ":" + std::to_string(g.line) + ": [geometry]: " + e.what());
    }
    // Case-defined node groups, added as point groups so the topology carries them to every node copy.
    for (const GroupSpec& gs : spec.groups) {
        if (m.find_group(gs.name))
            throw InputError(spec.file + ":" + std::to_string(gs.line) + ": key 'groups." + gs.name + "': the mesh already has a group of that name");
        std::vector<int> candidates;
        if (!gs.within.empty()) {
            const auto* w = m.find_group(gs.within);
            if (!w) throw InputError(spec.file + ":" + std::to_string(gs.line) + ": key 'groups." + gs.name + ".within': no group named '" + gs.within + "' in the mesh");
            candidates = w->nodes;
        } else {
            for (int k = 0; k < m.n_nodes(); ++k) candidates.push_back(k);
        }
        mesh::PhysicalGroup grp;
        grp.name = gs.name;
        grp.dim = 0;
        grp.within = gs.within;                        // copies on the within group's bodies only (topology)
        grp.every_copy = gs.box && gs.within.empty();  // a box alone: every node copy in it
        if (gs.box) {
            const auto& b = *gs.box;
            const double tol = 1e-9 * std::max({1.0, std::abs(b[0]), std::abs(b[1]), std::abs(b[2]), std::abs(b[3])});
            for (int k : candidates)
                if (m.xy[2 * k] >= b[0] - tol && m.xy[2 * k] <= b[2] + tol && m.xy[2 * k + 1] >= b[1] - tol && m.xy[2 * k + 1] <= b[3] + tol)
                    grp.nodes.push_back(k);
        } else {
            double best = 1e300;
            for (int k : candidates) best = std::min(best, std::hypot(m.xy[2 * k] - (*gs.nearest)[0], m.xy[2 * k + 1] - (*gs.nearest)[1]));
            for (int k : candidates)
                if (std::hypot(m.xy[2 * k] - (*gs.nearest)[0], m.xy[2 * k + 1] - (*gs.nearest)[1]) <= best * (1 + 1e-12) + 1e-15) grp.nodes.push_back(k);
        }
        if (grp.nodes.empty())
            throw InputError(spec.file + ":" + std::to_string(gs.line) + ": key 'groups." + gs.name + "': selects no node of the mesh");
        std::sort(grp.nodes.begin(), grp.nodes.end());
        m.groups.push_back(std::move(grp));
    }
    MeshNames names;
    names.regions = m.regions;
    for (const auto& grp : m.groups) names.groups.push_back(grp.name), names.group_dims.push_back(grp.dim);
    check_against_mesh(spec, names);
    return m;
}


bool needs_topology(const CaseSpec& spec) {
    if (spec.geometry.split_all) return true;
    for (const auto& m : spec.materials)
        if (m.fracture.present) return true;
    for (const auto& i : spec.interfaces)
        if (i.kind != "tied") return true;
    return false;
}

mesh::TopologyOptions topology_options(const CaseSpec& spec, const mesh::Mesh& m) {
    mesh::TopologyOptions opt;
    for (const auto& region : m.regions) {
        auto it = spec.region_material.find(region);
        const int mi = it == spec.region_material.end() ? -1 : spec.material_index(it->second);
        const bool crackable = mi >= 0 && spec.materials[mi].fracture.present;
        if (spec.geometry.split_all && !crackable)
            throw InputError(spec.file + ":" + std::to_string(spec.geometry.line) + ": key 'geometry.split': \"all\" makes every "
                             "edge crackable, but region '" + region + "' has a material without a [materials." +
                             (mi >= 0 ? spec.materials[mi].name : std::string("?")) + ".fracture] table");
        opt.regions.push_back({region, crackable});
    }
    for (const auto& i : spec.interfaces) {
        mesh::InterfaceRule r;
        r.region_a = i.region_a;
        r.region_b = i.region_b;
        r.kind = i.kind == "dry" ? mesh::InterfaceKind::dry : i.kind == "bonded" ? mesh::InterfaceKind::bonded : mesh::InterfaceKind::tied;
        opt.interfaces.push_back(r);
    }
    opt.split_all = spec.geometry.split_all;
    if (spec.geometry.type == "wall" && spec.geometry.wall.unit_cracks == "middle") opt.crack_group = "unit_cracks";
    return opt;
}

namespace {
std::string body_list(const mesh::Mesh& m, const std::vector<int>& bodies) {
    std::string s;
    for (int b : bodies) {
        std::string region = "?";
        for (int t = 0; t < m.n_triangles(); ++t)
            if (m.tri_body[t] == b) {
                region = m.tri_region[t] >= 0 ? m.regions[m.tri_region[t]] : "(no region)";
                break;
            }
        s += (s.empty() ? "" : ", ") + std::to_string(b) + " (region '" + region + "')";
    }
    return s;
}
}  // namespace

// Groups that loads, supports and initial conditions name, against the node copies of the split mesh
// (mesh/topology.hpp, "Groups of the split mesh"): a group whose node is split between bodies with no rule to
// choose one is refused; a curve group that left out the copies of other bodies at its ends is reported.
void check_group_bodies(const CaseSpec& spec, const mesh::Topology& topo) {
    struct Use {
        std::string key, group;
        int line;
    };
    std::vector<Use> uses;
    for (std::size_t si = 0; si < spec.stages.size(); ++si) {
        const std::string p = "stages." + std::to_string(si + 1);
        for (std::size_t i = 0; i < spec.stages[si].loads.size(); ++i)
            uses.push_back({p + ".loads." + std::to_string(i + 1) + ".group", spec.stages[si].loads[i].group, spec.stages[si].loads[i].line});
        for (std::size_t i = 0; i < spec.stages[si].supports.size(); ++i)
            uses.push_back({p + ".supports." + std::to_string(i + 1) + ".group", spec.stages[si].supports[i].group,
                            spec.stages[si].supports[i].line});
    }
    for (std::size_t i = 0; i < spec.initial.size(); ++i)
        uses.push_back({"initial." + std::to_string(i + 1) + ".group", spec.initial[i].group, spec.initial[i].line});
    const mesh::Mesh& m = topo.mesh;
    std::vector<std::string> warned;
    for (const Use& u : uses) {
        const mesh::PhysicalGroup* g = m.find_group(u.group);
        if (!g) continue;
        if (!g->split_bodies.empty()) {
            const double x = m.xy[2 * g->split_node], y = m.xy[2 * g->split_node + 1];
            char at[96];
            std::snprintf(at, sizeof at, "(%.6g, %.6g) m", x, y);
            throw InputError(spec.file + ":" + std::to_string(u.line) + ": key '" + u.key + "': group '" + u.group +
                             "' has a node at " + at + " that belongs to bodies " + body_list(m, g->split_bodies) +
                             ", which a joint separates: a point group cannot say which body's copy it means and would "
                             "drive all of them. Use a curve or surface group of that body, or a [groups] entry with "
                             "`within` a group of that body");
        }
        if (!g->left_out_bodies.empty() && std::find(warned.begin(), warned.end(), u.group) == warned.end()) {
            warned.push_back(u.group);
            std::fprintf(stderr, "warning: %s:%d: key '%s': group '%s' takes its nodes on bodies %s only; the copies of "
                         "bodies %s at the same points (shared corners) are not part of it\n",
                         spec.file.c_str(), u.line, u.key.c_str(), u.group.c_str(), body_list(m, g->bodies).c_str(),
                         body_list(m, g->left_out_bodies).c_str());
        }
    }
}

mesh::Topology build_topology_only(const CaseSpec& spec, mesh::RoughnessStats* roughness) {
    mesh::Mesh m = make_mesh(spec);
    try {
        mesh::TopologyOptions opt = topology_options(spec, m);
        if (!needs_topology(spec))  // no joints and no cracks: every body is tied into one continuum, as in a run
            for (std::size_t a = 0; a < m.regions.size(); ++a)
                for (std::size_t b = a; b < m.regions.size(); ++b)
                    opt.interfaces.push_back({m.regions[a], m.regions[b], mesh::InterfaceKind::tied});
        mesh::Topology topo = mesh::build_topology(m, opt);
        check_group_bodies(spec, topo);
        if (spec.geometry.joint_roughness > 0) {
            try {
                const mesh::RoughnessStats rs = mesh::roughen_dry_joints(
                    topo, spec.geometry.joint_roughness, spec.geometry.roughness_wavelength,
                    static_cast<std::uint64_t>(spec.geometry.roughness_seed));
                if (roughness) *roughness = rs;
                if (rs.points == 0) throw mesh::MeshError("the mesh has no dry joint face to roughen (no [[interfaces]] of kind \"dry\" touches)");
            } catch (const mesh::MeshError& e) {
                throw InputError(spec.file + ":" + std::to_string(spec.geometry.line) + ": key 'geometry.joint_roughness': " + e.what());
            }
        }
        return topo;
    } catch (const mesh::MeshError& e) {
        throw InputError(spec.file + ": [[interfaces]] / [geometry]: " + e.what());
    }
}

Model build_scene(const CaseSpec& spec) {
    // With joint_roughness, build_topology_only refuses a case without a dry joint (nothing to roughen).
    if (!needs_topology(spec) && !(spec.geometry.joint_roughness > 0)) return build_model(spec, make_mesh(spec));
    return build_model(spec, build_topology_only(spec));
}

}  // namespace fdem
