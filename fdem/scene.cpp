// fdem/scene.cpp: see scene.hpp.
#include "fdem/scene.hpp"

#include <algorithm>

#include "fdem/errors.hpp"
#include "fdem/simulation.hpp"

namespace fdem {

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

mesh::Topology build_topology_only(const CaseSpec& spec, mesh::RoughnessStats* roughness) {
    mesh::Mesh m = make_mesh(spec);
    try {
        mesh::TopologyOptions opt = topology_options(spec, m);
        if (!needs_topology(spec))  // no joints and no cracks: every body is tied into one continuum, as in a run
            for (std::size_t a = 0; a < m.regions.size(); ++a)
                for (std::size_t b = a; b < m.regions.size(); ++b)
                    opt.interfaces.push_back({m.regions[a], m.regions[b], mesh::InterfaceKind::tied});
        mesh::Topology topo = mesh::build_topology(m, opt);
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
