// fdem/case.hpp: a simulation case as read from its TOML file, validated, in SI units.
//
// The loader checks every key: missing required keys, wrong types, unknown keys (with a suggestion),
// non-physical values, references to groups or monitors that do not exist, stages that can never end.
// All problems found are reported together, each as "FILE:LINE: key 'a.b.c': what was expected".
// Values given with --set are reported as coming from "--set".
#pragma once

#include <array>
#include <cstdint>
#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "mesh/macro.hpp"
#include "mesh/wall.hpp"

namespace fdem {

enum class Plane { stress, strain };

// Cohesive properties ([K25] Eqs. 6-13, fracture/README.md): the fracture of a material's interior, or a bonded (mortared) interface.
// NaN = not given. Give penalty (Pa) OR normal_stiffness and shear_stiffness (Pa/m).
struct JointSpec {
    bool present = false;
    double tensile_strength = std::nan("");       // f_t, Pa
    double cohesion = std::nan("");               // c, Pa
    double friction = std::nan("");               // phi, deg
    double residual_friction = std::nan("");      // phi_res after breaking (contact), deg
    double GI = std::nan("");                     // mode I fracture energy, J/m^2
    double GII = std::nan("");                    // mode II fracture energy, J/m^2
    double penalty = std::nan("");                // p_j, Pa
    bool penalty_auto = false;                    // penalty = "auto": p_j from the element size (fracture/README.md)
    double penalty_ref = std::nan("");            // Pa, with "auto": the penalty where the mesh allows it (default 10 E)
    double normal_stiffness = std::nan("");       // k_n, Pa/m
    double shear_stiffness = std::nan("");        // k_s, Pa/m
    bool keep_friction = false;                   // shear_softening = "cohesion": friction kept while c softens
    bool mohr_coulomb = false;                    // law = "mohr_coulomb": fracture/mc_law.hpp (no G_I, G_II)
    double compressive_strength = std::nan("");   // Pa, compressive cap f_c (optional; NaN = none)
    bool composite = false;                       // law = "composite" (fracture/composite_law.hpp)
    double compressive_energy = std::nan("");     // J/m^2, G_c of the composite law's cap (NaN = none)
    double cap_shear_factor = std::nan("");       // -, C_s of the composite law's cap (NaN = none)
    bool extrinsic = false;                       // insertion = "extrinsic": materials only (fracture/README.md)
    double contact_penalty = std::nan("");        // Pa, normal penalty of the crack faces (materials; NaN: p_j)
    int line = 0;
};

// How two regions meet (fdem/README.md "Contact", cases/REFERENCE.md "interfaces"): tied (one continuum), bonded (cohesive element, then contact),
// dry (contact with Coulomb friction only). region_a == region_b: two different bodies of one region.
struct InterfaceSpec {
    std::string region_a, region_b;
    std::string kind;                              // "tied" | "bonded" | "dry"
    double friction = std::nan("");               // dry: phi, deg
    double normal_penalty = std::nan("");         // p_n, Pa   (or normal_stiffness)
    double normal_stiffness = std::nan("");       // k_n, Pa/m
    double tangential_penalty = std::nan("");     // p_t, Pa   (or shear_stiffness; default: the normal one)
    double shear_stiffness = std::nan("");        // k_s, Pa/m
    double restitution = 1;                        // dry: coefficient of restitution e of the normal contact, (0, 1]
    JointSpec bond;                                // bonded: the cohesive law (its stiffness also serves contact)
    int line = 0;
};

// Compression softening of a material's triangles ([materials.NAME.crushing], fdem/plasticity.hpp): the M-DEM
// macro-blocks' crushing. NaN = not given.
struct CrushingSpec {
    bool present = false;
    double compressive_strength = std::nan("");  // f_c, Pa (> 0)
    double Gc = std::nan("");                    // compressive fracture energy G_c, J/m^2 (> 0)
    int line = 0;
};

struct Material {
    std::string name;
    double E = 0;                // Young's modulus, Pa
    double nu = 0;               // Poisson's ratio, -
    double density = 0;          // kg/m^3
    double viscous_damping = 0;  // fraction of the element's critical viscous damping xi, - ([M04] ch. 4)
    JointSpec fracture;          // [materials.NAME.fracture]: present = the material may crack inside
    int line = 0;
    CrushingSpec crushing;       // [materials.NAME.crushing]: present = its triangles soften in compression
};

struct GeometrySpec {
    std::string type;  // "rectangle" | "gmsh" | "msh" | "wall" | "macro" | "macro_wall"
    // rectangle
    double x0 = 0, y0 = 0;  // lower-left corner, m
    double width = 0;       // m
    double height = 0;      // m
    double mesh_size = 0;   // target triangle size, m
    // gmsh (.geo script) / msh (mesh file); paths relative to the case file
    std::string file;
    double size_factor = 1;  // multiplies the .geo script's mesh sizes, -
    double min_angle = 10;   // deg, smallest triangle angle accepted (sliver check)
    bool split_all = false;  // classic FDEM limit: every edge of the mesh crackable (needs fracture properties)
    // Uneven bearing at dry joints (mesh/roughness.hpp): each body's dry-joint faces pulled inwards by a smooth
    // random offset in [0, joint_roughness] m with the given wavelength (m); 0 = flat faces.
    double joint_roughness = 0;
    double roughness_wavelength = 0;
    int roughness_seed = 1;
    // wall: the masonry wall generator; the TOML keys are the WallSpec field names (mesh/wall.hpp)
    mesh::WallSpec wall;
    // macro: the macro-block pier generator (M-DEM); the TOML keys are the MacroPierSpec field names (mesh/macro.hpp)
    mesh::MacroPierSpec macro;
    // macro_wall: the macro-block wall with one row of openings; the TOML keys are the MacroWallSpec field names
    mesh::MacroWallSpec macro_wall;
    int line = 0;
};

// A factor that varies in time, tau (s) counted from the start of the stage whose block sets it:
//   "sin":   offset + amplitude sin(omega tau + phase)   (amplitude, offset: -; omega: rad/s; phase: rad)
//   "table": points [[tau, factor], ...], linear between points, held at the first / last factor outside them.
// type "" = none: the factor is 1.
struct TimeFunction {
    std::string type;
    double amplitude = 1, omega = 0, phase = 0, offset = 0;
    std::vector<double> t, f;  // table: times (s, increasing) and factors (-)
    bool present() const { return !type.empty(); }
    double operator()(double tau) const;
};

// A [[stages.loads]] block: a load of one kind (fdem/load.hpp: force, pressure, spring, foundation) on a group, kept
// (and ramped from its previous value) in later stages until a block of the same kind on the group replaces it.
struct LoadSpec {
    std::string group;
    std::string kind;  // the key of its kind (fdem/load.hpp), as given: "force", "pressure", "spring", "foundation"
    // The fields of the force, pressure and spring kinds (their files read and use them; fdem/case_json.cpp and
    // fdem/limit_export.cpp read them too).
    bool is_pressure = false;
    std::array<double, 2> force{0, 0};  // total force on the group, N (whole thickness), distributed by tributary length
    double pressure = 0;                // Pa, acting against the current outward normal of the group's edges
    double ramp = 0;                    // s, linear ramp from the previous value (spring: smooth (1 - cos) ramp-up
                                        // of the anchor's velocity, like a prescribed velocity)
    // spring = { component, stiffness, velocity }: a compliant actuator. A spring of stiffness k (N/m) pulls the
    // group (force shared as for a force load) towards an anchor that starts at the group's mean position and moves
    // at `velocity` (m/s) in one component: F = k (anchor - mean position). The other component is left free.
    bool is_spring = false;
    int spring_component = 0;
    double spring_stiffness = 0;         // N/m
    double spring_velocity = 0;          // m/s
    TimeFunction function;               // multiplies the force or pressure (after its ramp); not for springs
    // The parameters of a kind that has no field above (SI units, named by their key in the block): a kind's file
    // reads and uses them without changing this struct (foundation: "normal", "shear", Pa/m).
    std::map<std::string, double> param;
    int line = 0;
};

enum class DofMode { inherit, free, fixed, velocity, protocol, rigid, body };
// The mode's name in fdem check --json and limit_model.json ("rigid_body" for body).
inline const char* to_string(DofMode m) {
    switch (m) {
        case DofMode::free: return "free";
        case DofMode::fixed: return "fixed";
        case DofMode::velocity: return "velocity";
        case DofMode::protocol: return "protocol";
        case DofMode::rigid: return "rigid";
        case DofMode::body: return "rigid_body";
        default: return "inherit";
    }
}

// A support on a group: per component free, fixed, a prescribed velocity (smooth ramp-up), a
// piecewise-linear displacement-versus-time protocol, or rigid: the group's nodes share one velocity in that
// component, free as a whole (e.g. rigid = "y" with vx on a loading beam: the beam stays horizontal, moves up
// and down freely, and cannot rotate), or body (rigid = "body", both components): the group moves as one rigid body,
// translating and rotating under its resultant force and moment, free. Kept in later stages until changed.
struct SupportSpec {
    std::string group;
    std::array<DofMode, 2> mode{DofMode::inherit, DofMode::inherit};
    std::array<double, 2> velocity{0, 0};  // m/s
    double ramp = 0;                       // s, smooth (1 - cos) ramp-up of a prescribed velocity; for a protocol
                                           // or cyclic support: the corner-smoothing time (see Simulation)
    // protocol for one component: times (s, from the stage start) and displacements (m, relative to the stage start)
    std::vector<double> protocol_t, protocol_u;
    TimeFunction function;  // multiplies the prescribed velocities vx, vy (after their ramp)
    // Servo-controlled loading rate (vx / vy only): the prescribed velocity times a factor in [servo_min, 1] that
    // follows the model's unbalanced-force ratio R (the stage's `equilibrium` measure): it shrinks while the ratio,
    // averaged over servo_time, is above servo_ratio and grows back towards 1 while it is below. 0: no servo.
    double servo_ratio = 0;   // -, target unbalanced-force ratio
    double servo_time = 0;    // s, response time of the controller (e-folding time of the factor and of R's mean)
    double servo_min = 0.01;  // -, smallest velocity factor
    int line = 0;
};

// Initial conditions of a group's nodes (a region is a group too), applied in this order before the first stage:
// a rigid rotation of their placement by `rotation` (deg, counter-clockwise) about `center` (stress-free: the
// triangles only turn; displacements are then measured from the unrotated mesh), then the velocity
// v = velocity + omega x (x - center) with `angular_velocity` omega (rad/s, counter-clockwise).
struct InitialSpec {
    std::string group;
    std::array<double, 2> velocity{0, 0};  // m/s
    double angular_velocity = 0;           // rad/s
    double rotation = 0;                   // deg
    std::array<double, 2> center{0, 0};    // m
    int line = 0;
};

// A node group defined in the case: the nodes inside a box, or the node(s) nearest to a point
// (every copy of a split node at that place).
struct GroupSpec {
    std::string name;
    std::optional<std::array<double, 4>> box;     // [xmin, ymin, xmax, ymax], m
    std::optional<std::array<double, 2>> nearest;  // [x, y], m
    std::string within;                            // optional: only nodes of this physical group
    int line = 0;
};

struct MonitorSpec {
    std::string name;
    std::string type;  // "displacement" | "velocity" | "reaction" | "load" | "tilt" | "rotation"
    std::string group;
    int component = 0;  // 0 = x, 1 = y
    std::string unit() const;
    int line = 0;
};

struct StageSpec {
    std::string name;
    int line = 0;
    // termination (at least one of duration / until / equilibrium)
    std::optional<double> duration;      // s
    std::optional<std::string> until_monitor;
    double until_value = 0;              // in the monitor's unit
    std::optional<double> equilibrium;   // unbalanced-force ratio, -
    // With equilibrium: the largest |sum of the supports' reactions + the applied loads| / |applied loads| (the
    // resultants, gravity included) at which the stage may end: the supports carry what is applied, not only the
    // forces' ratio is small (a wall bouncing on its base has a small ratio and a base reaction 6 % off its weight).
    double equilibrium_reactions = 0.01;
    std::optional<double> max_duration;  // s, bound for until / equilibrium
    // past_peak = { load, displacement, drop, travel, smooth }: the stage also ends once the load monitor's
    // magnitude, averaged over `smooth` of displacement, has stayed below (1 - drop) times the largest value that
    // average reached in this stage while the displacement monitor moved by at least `travel` (both in the
    // displacement monitor's unit; smooth defaults to travel / 4): a pushover run to its peak and a stated length
    // of its descending branch. It never ends a stage alone: the stage still needs duration, until (the largest
    // displacement) or max_duration.
    struct PastPeak {
        std::string load, displacement;
        double drop = 0, travel = 0, smooth = 0;
        int line = 0;
    };
    std::optional<PastPeak> past_peak;
    // gravity: vector (m/s^2), ramp (s), and a slow counter-clockwise rotation of the vector (deg/s, tilting tests)
    std::optional<std::array<double, 2>> gravity;
    double gravity_ramp = 0;
    double tilt_rate = 0;
    TimeFunction gravity_function;  // multiplies gravity from this stage's start; kept until a stage sets gravity
    std::optional<double> local_damping;  // alpha of the local damping [C79], 0 <= alpha < 1
    // Time constant tau (s) of the moving mean each DOF's velocity is measured against for the sign of the local
    // damping force: -alpha |f| sign(v - vbar_tau). 0 (default): the absolute velocity, as in [C79]. A steady motion
    // (a wall driven at a constant rate) is then not braked: only fluctuations faster than tau are damped. Kept by
    // later stages that do not set it.
    std::optional<double> local_damping_filter;
    // Contact dashpots: fraction xi of critical damping at the stiffest contact spring's frequency (0 <= xi <= 0.5);
    // kept by later stages that do not set it, like local_damping. See ContactSystem::set_dashpot.
    std::optional<double> contact_damping;
    // Mass-proportional (Rayleigh alpha, Belytschko, Liu & Moran 2000) damping a (1/s): f = -a m v on free nodes and
    // rigid groups; a mode of angular frequency omega is damped at a / (2 omega) of critical. Kept by later stages
    // that do not set it.
    std::optional<double> mass_damping;
    std::vector<LoadSpec> loads;
    std::vector<SupportSpec> supports;
    std::optional<double> history_interval;   // s
    std::optional<double> snapshot_interval;  // s
};

struct ReferenceSpec {
    std::string monitor;   // monitor compared
    std::string quantity;  // "peak" (largest absolute value) | "first_peak" (before the first cohesive break) | "final"
    double value = 0;      // in the monitor's unit
    double tolerance = 0;  // relative, for the pass/fail line (0: report only)
    std::string source;
    bool present = false;
};

struct CaseSpec {
    std::string file;  // path of the case file
    std::string dir;   // its folder (relative paths in the case are taken from here)
    std::string name, description;
    double thickness = 0;  // out-of-plane thickness, m
    Plane plane = Plane::stress;
    GeometrySpec geometry;
    std::vector<Material> materials;
    std::map<std::string, std::string> region_material;  // region (2D physical group) -> material name
    std::vector<GroupSpec> groups;
    std::vector<InterfaceSpec> interfaces;
    double contact_buffer = 0;  // m, NBS buffer; 0 = smallest contact edge / 5
    std::vector<MonitorSpec> monitors;
    std::vector<InitialSpec> initial;  // [[initial]] blocks
    std::vector<StageSpec> stages;
    double safety = 0.8;  // fraction of the stable time step used, -
    // Inertial mass multiplier for quasi-static runs (density scaling, as UDEC/3DEC do): the time step grows by
    // sqrt(mass_scale); gravity keeps the physical mass. 1 = physical dynamics.
    double mass_scale = 1;
    // mass_scaling = "per_node": after mass_scale, every node whose joint or contact springs are not stable at 4/3 of
    // the triangles' step raises its inertial mass (with its tied copies) just enough to be (the Itasca codes'
    // node-by-node density scaling; integrator.cpp scale_node_masses). false = "uniform", the default.
    bool per_node_mass = false;
    // numerics.energy_audit = true: the work each part's forces (triangles, cohesive joints, contact) do on the nodes
    // is summed every step and set against what the part holds and dissipated, in run.log every 1000 steps and in
    // the message of a failed energy check (Simulation::audit_text). A diagnostic: a serial pass over the nodes per step.
    bool energy_audit = false;
    std::optional<double> dt_override;  // s, a fixed time step (tests of the stability limit), bypasses the safety factor
    double history_interval = 0;   // s; 0 = every 100 steps
    double snapshot_interval = 0;  // s; 0 = only at the end of each stage
    // Checkpoints (fdem/checkpoint.hpp): one every checkpoint_interval s of simulated time and/or every
    // checkpoint_wall_interval s of wall-clock time; 0 = none (a stop by signal writes one all the same).
    double checkpoint_interval = 0;       // s (simulated)
    double checkpoint_wall_interval = 0;  // s (wall clock)
    // Hash of the case as resolved (the TOML after --set overrides, without the [output] checkpoint keys): a
    // checkpoint written for another case is refused on restart.
    std::uint64_t resolved_hash = 0;
    // Joint record of dry joints (cracks.csv): a dry joint segment is recorded the first time its opening at an end
    // exceeds joint_open, and the first time the mean slip of its ends exceeds joint_slip.
    double joint_open = 1e-4;  // m
    double joint_slip = 1e-4;  // m
    std::string curve_x, curve_y;  // monitors forming the load-displacement curve (optional)
    int curve_sign = 0;            // 1 / -1: the load's sign the tools apply (0: not stated, the tools' own rule)
    ReferenceSpec reference;
    std::vector<std::pair<std::string, std::string>> overrides;  // --set key=value as given

    int material_index(const std::string& name) const;
    const MonitorSpec* find_monitor(const std::string& name) const;
};

// Reads and validates a case file. `overrides` are "dotted.key=value" strings (the --set option);
// a value is parsed as TOML and taken as a string if that fails. Throws InputError listing every problem.
// Warnings (not errors) for values outside the usual range of masonry and rock in SI units, each naming the file,
// the key and the likely unit mix-up (E in MPa, a thickness or length in mm, a density in t/m^3): a case that reads
// fine can still be a unit slip. Printed by fdem check, run and mesh on stderr.
std::vector<std::string> plausibility_warnings(const CaseSpec& spec);

// keys_read (optional): every key the reader asked for, sorted, as cases/REFERENCE.md writes it
// ("stages[].supports[].vx", "materials.NAME.E"); tests/core/test_case_reference.cpp checks them against it.
CaseSpec load_case(const std::string& path, const std::vector<std::string>& overrides = {},
                   std::vector<std::string>* keys_read = nullptr);

// Checks that concern the mesh: every region has a material, every group a case refers to exists.
// `groups` are the mesh's physical group names, `regions` its 2D physical groups. Throws InputError.
struct MeshNames {
    std::vector<std::string> regions;
    std::vector<std::string> groups;
    std::vector<int> group_dims;
};
void check_against_mesh(const CaseSpec& spec, const MeshNames& names);

}  // namespace fdem
