// fdem/simulation.cpp: the Simulation object around the integrator: set-up (blocks, ties, time step, history header),
// monitors, energies and their checks, and the outputs (history rows, snapshots, summary.json). The step itself is in
// step.cpp (its time step and tied groups in integrator.cpp), the stages (supports, loads, protocols, servos, their
// endings) in stages.cpp, the run loop with its progress, signals and failures in run.cpp, checkpoints in
// checkpoint.cpp; sim_state.hpp holds the state and caches, sim_detail.hpp what the files share.
#include "fdem/simulation.hpp"
#include "fdem/version.hpp"

#include <omp.h>
#include <unistd.h>

#include <csignal>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "fdem/common/errors.hpp"
#include "fdem/sim_detail.hpp"

namespace fdem {

using namespace sim_detail;

double Energies::balance_error() const {
    const double lhs = external, rhs = kinetic + elastic + joint + contact + damping + viscous + fracture + friction;
    const double scale = std::max({std::abs(external), std::abs(kinetic) + std::abs(elastic) + std::abs(joint) + std::abs(contact) +
                                                           damping + viscous + fracture + friction, 1e-300});
    return std::abs(lhs - rhs) / scale;
}

Simulation::Simulation(CaseSpec spec, Model model, RunOptions options)
    : spec_(std::move(spec)), model_(std::move(model)), opt_(std::move(options)), inter_(spec_, model_) {
    // The control displacement of the damage records: the curve's x monitor, else the first displacement monitor.
    for (std::size_t i = 0; i < spec_.monitors.size(); ++i)
        if (spec_.monitors[i].name == spec_.curve_x) control_monitor_ = static_cast<int>(i);
    for (std::size_t i = 0; i < spec_.monitors.size() && control_monitor_ < 0; ++i)
        if (spec_.monitors[i].type == "displacement") control_monitor_ = static_cast<int>(i);
    // Gmsh sets OpenMP's thread count to its own General.NumThreads (1) when it initialises, so the count is
    // set here in every case: --threads, else OMP_NUM_THREADS, else every processor.
    int threads = opt_.threads;
    if (threads <= 0) {
        const char* env = std::getenv("OMP_NUM_THREADS");
        threads = env ? std::atoi(env) : 0;
    }
    omp_set_num_threads(threads > 0 ? threads : omp_get_num_procs());
    const int nn = model_.n_nodes(), nt = model_.n_triangles();
    supports_.dof_kind.assign(2 * nn, 0);
    supports_.dof_owner.assign(2 * nn, -1);
    supports_.dof_velocity.assign(2 * nn, 0.0);
    supports_.reaction.assign(2 * nn, 0.0);
    loads_.f_ext.assign(2 * nn, 0.0);
    scratch_.node_loaded.assign(nn, 0);
    scratch_.f_mod.assign(2 * nn, 0.0);
    scratch_.tri_forces.assign(6 * static_cast<std::size_t>(nt), 0.0);
    const int nb = std::max((nn + kBlock - 1) / kBlock, (nt + kBlock - 1) / kBlock);
    scratch_.tri_power.assign(nb, 0), scratch_.tri_bad.assign(nb, -1);
    scratch_.v2max = -1.0;
    out_.mon_ext.assign(spec_.monitors.size(), {0, 0, 0});
    out_.mon_first_peak.assign(spec_.monitors.size(), 0.0);
    crush_.setup(spec_, model_);
    build_ties();
    scale_node_masses();
    // The first contact detection, so that the first step's bound counts the edges near its candidate pairs only.
    inter_.refresh_contact(model_.x.data(), model_.v.data(), 0.0, -1.0);
    compute_dt();
    limits_.dt_initial = clock_.dt_logged = clock_.dt;
    // Derived quantities must be finite (issue 26: a huge mass_scale gave dt = 1e148 s, NaN energies and "completed").
    for (int k = 0; k < nn; ++k)
        if (!(std::isfinite(model_.mass[k]) && model_.mass[k] > 0) && !model_.mass.empty())
            throw InputError(spec_.file + ": node " + std::to_string(k) + " has a mass of " + sci(model_.mass[k]) +
                             " kg: expected a finite mass > 0 (check case.thickness, materials.*.density, numerics.mass_scale)");
    if (!(std::isfinite(clock_.dt) && clock_.dt > 0 && clock_.dt < 1e3))
        throw InputError(spec_.file + ": the time step comes out as " + sci(clock_.dt) +
                         " s: expected a finite step > 0 (check materials.*.E and density, case.thickness, "
                         "numerics.mass_scale and numerics.dt)");
    // A fixed step (numerics.dt) beyond the stable limit of this mesh would blow up the run after some steps: refused
    // here, so that `fdem check` says it (issue 51: a mesh study of a case with a fixed step at finer sizes).
    // The limit is that of the stage with the most local damping (the lowest).
    if (spec_.dt_override) {
        double alpha_max = 0;
        for (int s = 0; s < static_cast<int>(spec_.stages.size()); ++s) alpha_max = std::max(alpha_max, stage_alpha(s));
        set_step_limits(alpha_max, false);
        const double limit = std::min(limits_.dt_triangles, limits_.nodal.dt);
        const double tri = limits_.dt_triangles, springs = limits_.nodal.dt;
        set_step_limits(stage_alpha(0), false);
        if (*spec_.dt_override > limit)
            throw InputError(spec_.file + ": key 'numerics.dt': a fixed time step of " + sci(*spec_.dt_override) +
                             " s exceeds the stable limit of this mesh, " + sci(limit) + " s (triangles " + sci(tri) +
                             " s, nodes with their joint and contact springs " + sci(springs) + " s" +
                             (alpha_max > 0 ? ", at local damping " + sci(alpha_max) : std::string()) +
                             "): expected at most " + sci(limit) + " s, or no numerics.dt (the automatic step, "
                             "numerics.safety x the limit, follows the mesh)");
    }
    wall_start_ = wall_clock();
    cpu_start_ = cpu_clock();
    last_checkpoint_wall_ = wall_start_;
    if (spec_.checkpoint_interval > 0) out_.next_checkpoint = spec_.checkpoint_interval;
    if (!opt_.out_dir.empty()) {
        std::filesystem::create_directories(std::filesystem::path(opt_.out_dir) / "snapshots");
        // History header: time, step, stage, monitors, energies.
        history_ = "time,step,stage";
        for (const auto& m : spec_.monitors) history_ += "," + m.name;
        history_ += ",E_kin,E_el,E_joint,E_contact,W_ext,D_damp,D_visc,D_frac,D_fric,E_balance";
        if (inter_.has_joints())
            history_ += ",broken_unit_I,broken_unit_II,broken_unit_mixed,broken_interface_I,broken_interface_II,broken_interface_mixed";
        if (inter_.has_joints() && inter_.joints()->extrinsic_count() > 0) history_ += ",inserted";  // extrinsic elements in
        history_ += ",unbalanced\n";
    }
}

void Simulation::log(const std::string& line) {
    log_ += line + "\n";
    if (!opt_.quiet) std::cout << line << std::endl;
}

// Mean rigid rotation (deg, counter-clockwise) of a set of nodes from their reference placement: the angle of the
// least-squares rotation between the reference and current positions taken about their centroids (2D Kabsch:
// theta = atan2(sum X' x y', sum X' . x'), X' and x' relative to the centroids).
double Simulation::rotation_deg(const std::vector<int>& nodes, double lag) const {
    if (nodes.size() < 2) return 0.0;
    auto xn = [&](int d) { return model_.x[d] - lag * model_.v[d]; };  // positions at t^n, as the other monitors
    double cX = 0, cY = 0, cx = 0, cy = 0;
    for (int k : nodes) cX += model_.X[2 * k], cY += model_.X[2 * k + 1], cx += xn(2 * k), cy += xn(2 * k + 1);
    const double n = static_cast<double>(nodes.size());
    cX /= n, cY /= n, cx /= n, cy /= n;
    double dot = 0, cross = 0;
    for (int k : nodes) {
        const double X = model_.X[2 * k] - cX, Y = model_.X[2 * k + 1] - cY;
        const double x = xn(2 * k) - cx, y = xn(2 * k + 1) - cy;
        dot += X * x + Y * y;
        cross += X * y - Y * x;
    }
    return std::atan2(cross, dot) * 180 / kPi;
}

// A run whose energy grows with no work put in has gone unstable even if no triangle has inverted yet
// (e.g. contact springs stepped beyond their limit, which damping can hide for a while).
// Tolerance: 10 |W_ext| + 1e-9 J, plus the round-off of the energies summed: W_ext and the dissipations are running
// sums over the steps (each addition rounds by eps relative) and the held energies are sums over the elements, so
// their round-off is bounded by about (steps + 16) eps times the sum of the magnitudes.
// Before it stops the run, the row of the failing step is written to history.csv.
void Simulation::check_energy(const Energies& e) {
    const double held = e.kinetic + e.elastic + e.joint + e.contact + e.damping + e.viscous + e.fracture + e.friction;
    double mag = std::abs(e.external);
    for (double v : {e.kinetic, e.elastic, e.joint, e.contact, e.damping, e.viscous, e.fracture, e.friction}) mag += std::abs(v);
    const double roundoff = (static_cast<double>(clock_.steps) + 16.0) * std::numeric_limits<double>::epsilon() * mag;
    if (held > 10 * std::abs(e.external) + 1e-9 + roundoff) {
        if (!opt_.out_dir.empty() && out_.last_row_step != clock_.steps) append_history(history_row(e));
        // Name the largest holder: it points at the part that went unstable.
        const std::pair<const char*, double> parts[] = {{"kinetic", e.kinetic}, {"elastic (triangles)", e.elastic},
                                                        {"cohesive joints", e.joint}, {"contact", e.contact}};
        std::size_t big = 0;
        for (std::size_t i = 1; i < 4; ++i)
            if (parts[i].second > parts[big].second) big = i;
        std::string cause = "most of it " + std::string(parts[big].first) + " energy (" + sci(parts[big].second) + " J)";
        if (!spec_.dt_override && spec_.safety > 1)
            cause += "; numerics.safety = " + sci(spec_.safety) + " > 1 puts the time step beyond the stability limit: reduce numerics.safety below 1";
        else if (spec_.dt_override)
            cause += "; numerics.dt fixes the step at " + sci(clock_.dt) + " s against a stable limit of " +
                     sci(clock_.dt_limit) + " s";
        else if (joints_made_it(e))
            cause += "; the cohesive joints' forces gave out more energy than they hold and dissipated: the law's shear "
                     "curve depends on the compression and is not a potential (fracture/law.hpp), and oscillating joints "
                     "can pump energy; more local damping holds it down";
        else if (big == 3)
            cause += "; contact springs beyond their stable step: reduce numerics.safety or the contact penalty";
        else
            cause += "; unstable; reduce numerics.safety";
        const std::string crushed = crushed_broken_note();
        const std::string audit = spec_.energy_audit ? audit_text(e)
                                                     : "run again with --set numerics.energy_audit=true to see which "
                                                       "part's forces made it";
        fail("energy grew without work: " + sci(held) + " J held or dissipated against " + sci(e.external) +
             " J put in (" + (crushed.empty() ? "" : crushed + "; otherwise ") + cause + "); " + audit);
    }
}

// Compressive cap (fracture/law.hpp): an element that breaks while crushed hands its whole overlap, the plastic
// closure included, to contact, which pushes the faces apart with its own penalty (fracture/README.md). Empty when
// no broken element was crushed.
std::string Simulation::crushed_broken_note() const {
    const fracture::CohesiveSystem* j = inter_.joints();
    if (!j || !j->has_cap()) return "";
    long long n = 0;
    double largest = 0.0;
    for (int k = 0; k < j->size(); ++k)
        if (j->state(k) == fracture::JointState::broken && j->crushing(k) > 0.0) ++n, largest = std::max(largest, j->crushing(k));
    if (n == 0) return "";
    return std::to_string(n) + " cohesive element(s) broke while crushed (largest plastic closure " + sci(largest) +
           " m): contact took over their overlap, plastic closure included, and pushes it apart (fracture/README.md, "
           "compressive cap)";
}

// Energy audit (numerics.energy_audit). Phase 0, at the start of a step: the books' baseline on the first audited
// step, the velocities v^{n-1/2}. Phase 1, after the joints and contact added their forces: their sum (the joints'
// alone was copied by Interactions::add_forces). Phase 2, after the node loop: each part's work over the step,
// dt f . (v^{n-1/2} + v^{n+1/2}) / 2, the external work's rule; the contact forces are the sum less the joints' (to
// rounding: the run's own sum is left as it is, so the audit changes no bit of the run).
void Simulation::audit_step(int phase, double dt) {
    const std::size_t n2 = model_.x.size();
    if (phase == 0) {
        if (audit_.t0 < 0) {
            audit_parts(energies(), audit_.base.data());
            audit_.t0 = clock_.time;
        }
        audit_.fj.resize(n2);  // (filled by Interactions::add_forces; audit_.f by phase 1)
        audit_.v.assign(model_.v.begin(), model_.v.end());
        return;
    }
    if (phase == 1) {
        audit_.f.assign(scratch_.f_mod.begin(), scratch_.f_mod.end());
        return;
    }
    const int nn = model_.n_nodes();
    const double* v = model_.v.data();
    double w[3] = {0, 0, 0}, h[3] = {0, 0, 0};
    // (the last step's length: on a change of step the work is f over (x^{n+1} - x^{n-1}) / 2, fdem/node_update.hpp)
    const double h1 = clock_.dt_last > 0 ? clock_.dt_last : dt;
    for (int k = 0; k < nn; ++k)
        for (int c = 0; c < 2; ++c) {
            const std::size_t d = 2 * static_cast<std::size_t>(k) + c;
            double ft = 0;
            for (int i = model_.inc_ptr[k]; i < model_.inc_ptr[k + 1]; ++i)
                ft += scratch_.tri_forces[2 * static_cast<std::size_t>(model_.inc_idx[i]) + c];
            const double f[3] = {ft, audit_.fj[d], audit_.f[d] - audit_.fj[d]};
            const double vbar = 0.5 * (audit_.v[d] + v[d]);
            for (int m = 0; m < 3; ++m) {
                w[m] += h1 != dt ? f[m] * (0.5 * (h1 * audit_.v[d] + dt * v[d])) : dt * f[m] * vbar;
                h[m] += 0.5 * dt * f[m] * v[d];
            }
        }
    for (int m = 0; m < 3; ++m) audit_.w[m] += w[m], audit_.half[m] = h[m];
}

// What each part holds and has dissipated (J): triangles (elastic, viscous element damping, crushing), cohesive
// joints (elastic, fracture, their friction, less the pre-peak energy inserted elements started with: that came in
// as work), contact (penalty energy, friction, dashpots).
void Simulation::audit_parts(const Energies& e, double* held) const {
    const contact::ContactSystem* c = inter_.contact();
    const double contact_friction = c ? c->friction_dissipation() : 0.0;
    held[0] = e.elastic + books_.D_visc + crush_.dissipated();
    held[1] = e.joint + inter_.fracture_dissipation() + (inter_.friction_dissipation() - contact_friction) -
              inter_.inserted_energy();
    held[2] = e.contact + contact_friction + inter_.contact_damping_dissipation();
}

std::array<Simulation::AuditPart, 3> Simulation::energy_audit(const Energies& e) const {
    std::array<AuditPart, 3> parts;
    if (audit_.t0 < 0) return parts;
    double held[3];
    audit_parts(e, held);
    for (int m = 0; m < 3; ++m) {
        parts[m].worked = 0.0 - (audit_.w[m] - audit_.half[m]);  // the nodes' work on the part, to t^n (+0, not -0)
        parts[m].grew = held[m] - audit_.base[m];
    }
    return parts;
}

// With the audit on: whether the cohesive joints hold more than half of the energy the run made from nothing.
bool Simulation::joints_made_it(const Energies& e) const {
    if (!spec_.energy_audit || audit_.t0 < 0) return false;
    const auto parts = energy_audit(e);
    double total = 0;
    for (const auto& q : parts) total += std::max(0.0, q.grew - q.worked);
    return total > 0 && parts[1].grew - parts[1].worked > 0.5 * total;
}

std::string Simulation::audit_text(const Energies& e) const {
    if (audit_.t0 < 0) return "energy audit: not started";
    const auto parts = energy_audit(e);
    static const char* names[3] = {"triangles", "cohesive joints", "contact"};
    std::string s = "energy audit at t = " + sci(clock_.time) + " s (since " + sci(audit_.t0) +
                    " s), work done on each part against the growth of what it holds and dissipated:";
    int worst = 0;
    double excess[3];
    for (int m = 0; m < 3; ++m) {
        excess[m] = parts[m].grew - parts[m].worked;
        if (excess[m] > excess[worst]) worst = m;
        s += std::string(m ? ";" : "") + " " + names[m] + " " + sci(parts[m].worked) + " J / " + sci(parts[m].grew) + " J";
    }
    if (excess[worst] > 0)
        s += "; the largest excess: " + std::string(names[worst]) + ", " + sci(excess[worst]) + " J more than worked";
    return s;
}

// Monitors describe the state at the last force evaluation t^n, where reactions and loads were computed:
// after a step x holds x^{n+1} = x^n + dt v^{n+1/2}, so the displacement at t^n is x - dt v (velocities are
// the half-step ones). Pairing u^{n+1} with R^n would put the force one step behind the displacement and
// bias the energy of hysteresis loops by about k dt times the integral of the squared velocity.
double Simulation::monitor_value(int i) const {
    const MonitorSpec& m = spec_.monitors[i];
    const double lag = clock_.steps > 0 ? clock_.dt : 0.0;
    if (m.type == "tilt") {
        // the angle of gravity from -y (counter-clockwise, deg): the stage's gravity vector as given (a tilted table
        // given as a tilted vector reads its angle) plus the rotation of tilt_rate at t^n
        const double g = std::hypot(gravity_.current[0], gravity_.current[1]);
        const double base = g > 0 ? std::atan2(gravity_.current[0], -gravity_.current[1]) * 180 / kPi : 0.0;
        return base + (gravity_.tilt_deg - gravity_.tilt_rate * lag);
    }
    const auto& grp = model_.group(m.group);
    if (m.type == "rotation") return rotation_deg(grp.nodes, lag);
    const int c = m.component;
    double s = 0;
    if (m.type == "displacement" || m.type == "velocity") {
        for (int k : grp.nodes)
            s += m.type == "displacement" ? model_.x[2 * k + c] - lag * model_.v[2 * k + c] - model_.X[2 * k + c] : model_.v[2 * k + c];
        return grp.nodes.empty() ? 0.0 : s / static_cast<double>(grp.nodes.size());
    }
    if (m.type == "reaction") {
        for (int k : grp.nodes) s += supports_.dof_kind[2 * k + c] ? supports_.reaction[2 * k + c] : 0.0;
        return s;
    }
    for (int k : grp.nodes) s += loads_.f_ext[2 * k + c];  // load
    return s;
}

// Energies at t^n, the time of the last force evaluation (as the monitors). With leap-frog velocities the exact
// discrete identity is: trapezoidal work sum_k dt/2 (f^k + f^{k+1}) . v^{k+1/2} = K^n - K^0 with
// K^n = 1/2 m v^{n-1/2} . v^{n+1/2}. The step accumulates dt f^n . vbar^n, which runs half a step ahead:
// the trapezoidal work up to t^n is that sum minus dt/2 f^n . v^{n+1/2} (kept by the node loop), and likewise
// for damping. The elastic energy is evaluated at x^n = x - dt v; joint and contact energies are those of the
// last force evaluation, at x^n. Pairing K(v^{n+1/2}) with E(x^{n+1}) instead showed as a 2.8 % balance error
// on a vibrating pair of blocks (measured by the contact tests).
Energies Simulation::energies() const {
    Energies e;
    const int nn = model_.n_nodes(), nt = model_.n_triangles();
    const int nnb = (nn + kBlock - 1) / kBlock, ntb = (nt + kBlock - 1) / kBlock;
    std::vector<double> pk(nnb, 0.0), pe(ntb, 0.0);
    const bool stepped = clock_.steps > 0;
    std::vector<double> xn;
    const double* xe = model_.x.data();
    if (stepped) {
        xn.resize(model_.x.size());
        for (std::size_t i = 0; i < xn.size(); ++i) xn[i] = model_.x[i] - clock_.dt * model_.v[i];
        xe = xn.data();
    }
#pragma omp parallel for schedule(static) if (nnb > 1)
    for (int b = 0; b < nnb; ++b) {
        double s = 0;
        for (int k = b * kBlock; k < std::min(nn, (b + 1) * kBlock); ++k)
            s += 0.5 * model_.mass[k] * (model_.v[2 * k] * model_.v[2 * k] + model_.v[2 * k + 1] * model_.v[2 * k + 1]);
        pk[b] = s;
    }
#pragma omp parallel for schedule(static) if (ntb > 1)
    for (int b = 0; b < ntb; ++b) {
        double s = 0;
        for (int t = b * kBlock; t < std::min(nt, (b + 1) * kBlock); ++t)
            s += crush_.slot(t) < 0 ? triangle_energy(model_.tris[t], model_.mat[model_.tris[t].mat], xe)
                                    : crush_.energy(crush_.slot(t), model_.tris[t], xe);
        pe[b] = s;
    }
    for (double s : pk) e.kinetic += s;
    for (double s : pe) e.elastic += s;
    if (stepped) e.kinetic = books_.kinetic_n;
    // Extrinsic insertion: the pre-peak energy an inserted element starts with is put in, like work
    // (fracture/cohesive_system.hpp).
    e.external = books_.W_ext - (stepped ? books_.work_half : 0.0) + inter_.inserted_energy();
    e.damping = books_.D_damp - (stepped ? books_.damp_half : 0.0);
    e.viscous =
        books_.D_visc + books_.D_mass - (stepped ? books_.mass_half : 0.0) + inter_.contact_damping_dissipation();
    e.joint = inter_.joint_energy();
    e.contact = inter_.contact_energy(xe);
    e.fracture = inter_.fracture_dissipation() + crush_.dissipated();  // crushing work booked with fracture
    e.friction = inter_.friction_dissipation();
    return e;
}

void Simulation::write_history_row() {
    const Energies e = energies();
    append_history(history_row(e));
    if (clock_.steps > 0) check_energy(e);
}

std::string Simulation::history_row(const Energies& e) {
    // The row describes t^n, the time of the last force evaluation (see monitor_value).
    std::string row = format_double(clock_.steps > 0 ? clock_.time - clock_.dt : clock_.time) + "," +
                      std::to_string(clock_.steps) + "," + std::to_string(clock_.stage + 1);
    for (std::size_t i = 0; i < spec_.monitors.size(); ++i) {
        const double m = monitor_value(static_cast<int>(i));
        row += "," + format_double(m);
        auto& ext = out_.mon_ext[i];
        if (!out_.mon_ext_init) ext = {m, m, m};
        ext = {std::min(ext[0], m), std::max(ext[1], m), m};
        // The peak before the first cohesive element breaks (reference quantity "first_peak"): the rows up to the
        // first break, so that the ringing after a brittle break does not count as the strength.
        if (clock_.broken_total == 0 && std::abs(m) >= std::abs(out_.mon_first_peak[i])) out_.mon_first_peak[i] = m;
    }
    out_.mon_ext_init = true;
    for (double v : {e.kinetic, e.elastic, e.joint, e.contact, e.external, e.damping, e.viscous, e.fracture, e.friction, e.balance_error()})
        row += "," + format_double(v);
    if (const auto* c = inter_.counts())
        for (auto cls : {fracture::JointClass::unit_interior, fracture::JointClass::interface})
            for (auto mode : {fracture::FractureMode::mode_I, fracture::FractureMode::mode_II, fracture::FractureMode::mixed})
                row += "," + std::to_string(c->of(cls, mode));
    if (inter_.has_joints() && inter_.joints()->extrinsic_count() > 0)
        row += "," + std::to_string(inter_.joints()->extrinsic_count() - inter_.joints()->dormant_count());
    row += "," + format_double(books_.unbalanced_ratio) + "\n";
    return row;
}

// history.csv grows by one appended, flushed row at a time (a killed run loses at most the row being written);
// the file is created with its header on the first row.
void Simulation::append_history(const std::string& row) {
    out_.last_row_step = clock_.steps;
    if (opt_.out_dir.empty()) return;
    open_history();
    history_out_ << row;
    history_out_.flush();
}

void Simulation::open_history() {
    if (opt_.out_dir.empty() || history_out_.is_open()) return;
    const std::string path = (std::filesystem::path(opt_.out_dir) / "history.csv").string();
    history_out_.open(path, std::ios::binary | std::ios::trunc);
    if (!history_out_) throw RunError("cannot write " + path);
    history_out_ << history_;
    history_out_.flush();
    history_.clear();
}

void Simulation::flush_files() {
    if (opt_.out_dir.empty()) return;
    last_flush_ = wall_clock();
    const std::filesystem::path dir(opt_.out_dir);
    open_history();
    if (inter_.has_joints() || inter_.has_dry_joints()) {
        std::ostringstream header;
        fracture::write_cracks_csv_header(header);
        write_file_atomic((dir / "cracks.csv").string(), header.str() + inter_.cracks_csv());
    }
    write_file_atomic((dir / "run.log").string(), log_);
}

// The monitor's value that the [reference] compares: "peak" the largest absolute value of the run, "first_peak"
// the largest absolute value before the first cohesive element breaks (the whole run if none breaks), "final" the
// last value. From the history rows.
double Simulation::reference_value(int i) const {
    const auto& ext = out_.mon_ext[static_cast<std::size_t>(i)];
    const std::string& q = spec_.reference.quantity;
    if (q == "final") return ext[2];
    if (q == "first_peak") return out_.mon_first_peak[static_cast<std::size_t>(i)];
    return std::abs(ext[0]) > std::abs(ext[1]) ? ext[0] : ext[1];
}

bool Simulation::reference_past_peak(int i) const {
    if (spec_.reference.quantity != "peak") return true;
    if (!ending_.results.empty() && ending_.results.back().ended_by == "past_peak") return true;
    const auto& ext = out_.mon_ext[static_cast<std::size_t>(i)];
    const double peak = std::max(std::abs(ext[0]), std::abs(ext[1]));
    return peak > 0 && std::abs(ext[2]) < (1.0 - kPastPeakDrop) * peak;
}

double Simulation::history_interval() const {
    const StageSpec& st = spec_.stages[clock_.stage];
    return st.history_interval ? *st.history_interval : spec_.history_interval;
}

double Simulation::snapshot_interval() const {
    const StageSpec& st = spec_.stages[clock_.stage];
    return st.snapshot_interval ? *st.snapshot_interval : spec_.snapshot_interval;
}

double Simulation::control_displacement() const { return control_monitor_ >= 0 ? monitor_value(control_monitor_) : 0.0; }

// The dry joint record is checked where a history row is written (and at stage ends).
void Simulation::record_dry_joints() {
    if (inter_.has_dry_joints()) inter_.record_dry_joints(clock_.time, control_displacement(), model_.x.data());
}

// Whether a history row is written after the step that ends at time t as step number `step` (one rule for the
// write itself and for asking the contact module to evaluate its energy on that step).
bool Simulation::history_due(double t, long step) const {
    if (opt_.out_dir.empty()) return false;
    const double hi = history_interval();
    return hi > 0 ? t + 1e-9 * clock_.dt >= out_.next_history : (step % out_.history_every_steps) == 0;
}

void Simulation::write_summary(const std::string& status, const std::string& message) {
    Json j = Json::object();
    j["case"] = spec_.name;
    j["case_file"] = spec_.file;
    j["description"] = spec_.description;
    j["status"] = status;
    j["message"] = message;
    j["fdem_version"] = FDEM_VERSION;
    j["build"] = build_id();
    {
        char hex[17];
        std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(spec_.resolved_hash));
        j["case_hash"] = std::string(hex);  // the case as resolved (its TOML after --set), CaseSpec::resolved_hash
    }
    Json cols = Json::object();
    cols["time"] = "s";
    cols["step"] = "-";
    cols["stage"] = "-";
    for (const auto& m : spec_.monitors) cols[m.name] = m.unit();
    for (const char* c : {"E_kin", "E_el", "E_joint", "E_contact", "W_ext", "D_damp", "D_visc", "D_frac", "D_fric"}) cols[c] = "J";
    cols["E_balance"] = "-";
    cols["unbalanced"] = "-";
    if (inter_.has_joints()) {
        for (const char* c : {"broken_unit_I", "broken_unit_II", "broken_unit_mixed", "broken_interface_I", "broken_interface_II",
                              "broken_interface_mixed"})
            cols[c] = "-";
        if (inter_.joints()->extrinsic_count() > 0) cols["inserted"] = "-";
    }
    j["columns"] = cols;
    if (!spec_.curve_x.empty()) {
        Json c = Json::object();
        c["x"] = spec_.curve_x;
        c["y"] = spec_.curve_y;
        if (spec_.curve_sign != 0) c["sign"] = spec_.curve_sign;
        j["curve"] = c;
    }
    j["n_triangles"] = model_.n_triangles();
    j["n_nodes"] = model_.n_nodes();
    j["dt"] = clock_.dt;
    j["dt_stable_limit"] = clock_.dt_limit;
    j["dt_limiting_triangle"] = limits_.dt_element;
    j["steps"] = static_cast<long long>(clock_.steps);
    const double wall = status == "running" ? 0.0 : wall_time_;
    j["wall_time_s"] = wall;
    j["cpu_time_s"] = status == "running" ? 0.0 : cpu_time_;
    j["triangle_steps_per_s"] = wall > 0 ? static_cast<double>(clock_.steps) * model_.n_triangles() / wall : 0.0;
    j["threads"] = omp_get_max_threads();
    j["time"] = clock_.time;
    Json mons = Json::object();
    for (std::size_t i = 0; i < spec_.monitors.size(); ++i) {
        Json m = Json::object();
        m["min"] = out_.mon_ext[i][0];
        m["max"] = out_.mon_ext[i][1];
        m["final"] = out_.mon_ext[i][2];
        m["unit"] = spec_.monitors[i].unit();
        mons[spec_.monitors[i].name] = m;
    }
    j["monitors"] = mons;
    if (inter_.has_dry_joints()) {
        Json jr = Json::object();
        jr["open_threshold_m"] = inter_.open_threshold();
        jr["slip_threshold_m"] = inter_.slip_threshold();
        jr["segments"] = inter_.dry_joint_count();
        jr["opened"] = inter_.dry_open_count();
        jr["slipped"] = inter_.dry_slip_count();
        j["joint_record"] = jr;
    }
    Json stages = Json::array();
    for (const auto& r : ending_.results) {
        Json s = Json::object();
        s["name"] = r.name;
        s["ended_by"] = r.ended_by;
        s["time"] = r.time;
        s["steps"] = static_cast<long long>(r.steps);
        stages.push_back(s);
    }
    j["stages"] = stages;
    const Energies e = energies();
    Json en = Json::object();
    en["kinetic"] = e.kinetic;
    en["elastic"] = e.elastic;
    en["external_work"] = e.external;
    en["damping"] = e.damping;
    en["viscous"] = e.viscous;
    en["joint"] = e.joint;
    en["contact"] = e.contact;
    en["fracture"] = e.fracture;
    en["friction"] = e.friction;
    en["balance_error"] = e.balance_error();
    j["energy"] = en;
    Json set = Json::object();
    set["thickness_m"] = spec_.thickness;
    set["plane"] = spec_.plane == Plane::stress ? "stress" : "strain";
    set["geometry"] = spec_.geometry.type;
    if (spec_.geometry.type == "rectangle") set["mesh_size_m"] = spec_.geometry.mesh_size;
    if (!spec_.geometry.file.empty()) set["geometry_file"] = spec_.geometry.file;
    set["safety"] = spec_.safety;
    set["mass_scale"] = spec_.mass_scale;
    set["mass_scaling"] = spec_.per_node_mass ? "per_node" : "uniform";
    if (spec_.per_node_mass)
        set["mass_scaling_nodes_raised"] = limits_.mass_raised_nodes,
        set["mass_scaling_total_ratio"] = limits_.mass_raised_ratio;
    if (spec_.dt_override) set["dt_fixed_s"] = *spec_.dt_override;
    Json mats = Json::object();
    for (const auto& m : spec_.materials) {
        Json o = Json::object();
        o["E_Pa"] = m.E;
        o["nu"] = m.nu;
        o["density_kg_m3"] = m.density;
        o["viscous_damping"] = m.viscous_damping;
        mats[m.name] = o;
    }
    set["materials"] = mats;
    Json sd = Json::array();
    for (const auto& s : spec_.stages) {
        Json o = Json::object();
        o["name"] = s.name;
        if (s.local_damping) o["local_damping"] = *s.local_damping;
        if (s.local_damping_filter) o["local_damping_filter_s"] = *s.local_damping_filter;
        if (s.contact_damping) o["contact_damping"] = *s.contact_damping;
        if (s.mass_damping) o["mass_damping"] = *s.mass_damping;
        if (s.duration) o["duration_s"] = *s.duration;
        if (s.equilibrium) o["equilibrium"] = *s.equilibrium;
        sd.push_back(o);
    }
    set["stages"] = sd;
    Json ov = Json::object();
    for (const auto& [k, v] : spec_.overrides) ov[k] = v;
    set["overrides"] = ov;
    j["settings"] = set;
    if (spec_.reference.present) {
        const ReferenceSpec& ref = spec_.reference;
        Json r = Json::object();
        r["monitor"] = ref.monitor;
        r["quantity"] = ref.quantity;
        r["value"] = ref.value;
        r["source"] = ref.source;
        for (std::size_t i = 0; i < spec_.monitors.size(); ++i)
            if (spec_.monitors[i].name == ref.monitor) {
                const double got = reference_value(static_cast<int>(i));
                r["computed"] = got;
                r["past_peak"] = reference_past_peak(static_cast<int>(i));
                r["relative_error"] = ref.value != 0 ? (std::abs(got) - std::abs(ref.value)) / std::abs(ref.value) : 0.0;
            }
        j["reference"] = r;
    }
    write_file_atomic((std::filesystem::path(opt_.out_dir) / "summary.json").string(), j.dump());
}

}  // namespace fdem
