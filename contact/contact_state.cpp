// contact/contact_state.cpp: what ContactSystem holds and reports between steps: the loaded faces for snapshots,
// the normal energy at given positions, and the checkpoint (one field list for save and load).
#include <algorithm>
#include <cstdint>
#include <vector>

#include "contact/contact_system.hpp"
#include "contact/potential.hpp"

namespace fdem::contact {

std::vector<ContactSystem::LoadedEdge> ContactSystem::loaded_edges(const double* x, const double* v, double dt) const {
    std::vector<LoadedEdge> out;
    std::vector<PairParams> prm;
    const bool altitudes = resolve_params(dt, prm);
    PairBatch batch;
    std::vector<double> hist(kHistPerPair);
    const int np = static_cast<int>(pair_a_.size());
    for (int p = 0; p < np; ++p) {
        const int ab[2] = {pair_a_[p], pair_b_[p]};
        TriangleGeometry g[2];
        double vel[2][6];
        for (int i = 0; i < 2; ++i) {
            double T[6];
            gather(x, tri_ + 3 * ab[i], T);
            triangle_geometry(T, g[i], altitudes);
            // the faces as the last step had them (update_faces runs at the next step)
            g[i].faces = faces_.empty() ? 0 : static_cast<int>(faces_[ab[i]]);
            gather(v, tri_ + 3 * ab[i], vel[i]);
        }
        // the pair's friction history as it is (a copy: this changes nothing)
        std::copy(hist_.begin() + kHistPerPair * static_cast<std::ptrdiff_t>(p),
                  hist_.begin() + kHistPerPair * static_cast<std::ptrdiff_t>(p + 1), hist.begin());
        PairResult r;
        batch.clear(1);
        if (!batch.begin(g[0], g[1], prm[pair_law_[p]], false, hist.data(), r)) continue;
        batch.integrate();
        EdgeRecord rec[6];
        double f12[12], fd12[12];
        if (!batch.end(g[0], g[1], vel[0], vel[1], prm[pair_law_[p]], false, hist.data(), r, 0x3f, f12, fd12, rec)) continue;
        for (int s = 0; s < 6; ++s)
            if (rec[s].loaded) out.push_back({ab[s / 3], s % 3, ab[1 - s / 3], rec[s]});
    }
    return out;
}

double ContactSystem::normal_energy_at(const double* x) const {
    double en = 0.0;
    const int np = static_cast<int>(pair_a_.size());
    for (int p = 0; p < np; ++p) {
        double xa[6], xb[6];
        gather(x, tri_ + 3 * pair_a_[p], xa);
        gather(x, tri_ + 3 * pair_b_[p], xb);
        const ResolvedLaw& L = laws_[pair_law_[p]];
        PairParams prm;
        prm.thickness = thickness_;
        prm.distance_potential = L.normal_is_stiffness;
        prm.c = L.normal_is_stiffness ? 0.5 * L.normal : L.normal;
        en += pair_energy(xa, xb, prm);
    }
    return en;
}

// Checkpoint. The sizeof guard below fails the build when a field is added to ContactSystem (x86-64 libstdc++):
// add the field to save_state and load_state if it carries from one step to the next, then update the size.
void ContactSystem::save_state(StateWriter& w) const {
#if defined(__x86_64__) && defined(__GLIBCXX__)
    static_assert(sizeof(ContactSystem) == 1640, "ContactSystem changed: update state_io and this size");
#endif
    const_cast<ContactSystem*>(this)->state_io(w);  // (the writer only reads the fields)
}

void ContactSystem::load_state(StateReader& r) { state_io(r); }

template <class IO>
void ContactSystem::state_io(IO& io) {
    constexpr bool load = IO::loading;
    io.section("contact");
    std::int32_t slots = kHistPerPair;
    io.pod(slots);
    if constexpr (load)
        if (slots != kHistPerPair) throw StateError("contact: another number of friction history slots per pair");
    int nt = n_tri_, nn = n_nodes_;
    io.pod(nt), io.pod(nn);
    if constexpr (load)
        if (nt != n_tri_ || nn != n_nodes_) throw StateError("contact: another mesh");
    io.vec_sized(capable_, static_cast<std::size_t>(n_tri_), "contact-capable flags");
    std::uint64_t n_excluded = excluded_.size();
    io.pod(n_excluded);
    if constexpr (load)
        if (n_excluded != excluded_.size()) throw StateError("contact: excluded pairs of another mesh");
    for (auto& e : excluded_) io.vec(e);
    io.vec_sized(released_, released_.size(), "released vertices");
    io.pod(dirty_), io.pod(buffer_), io.pod(travel_);
    io.vec(items_);
    io.vec(pair_a_), io.vec(pair_b_), io.vec(pair_law_), io.vec(hist_);
    if constexpr (load) {
        const std::size_t np = pair_a_.size();
        if (pair_b_.size() != np || pair_law_.size() != np || hist_.size() != kHistPerPair * np)
            throw StateError("contact: inconsistent pair arrays");
        pair_hist_on_.resize(np);
        for (std::size_t p = 0; p < np; ++p) {
            char held = 0;
            for (int sl = 0; sl < 6; ++sl)
                for (int i = 0; i < kHistPerEdge; ++i)
                    if (hist_[kHistPerPair * p + kHistPerEdge * sl + i] != 0.0) held |= static_cast<char>(1 << sl);
            pair_hist_on_[p] = held;
        }
        for (std::size_t p = 0; p < np; ++p)
            if (pair_a_[p] < 0 || pair_a_[p] >= n_tri_ || pair_b_[p] < 0 || pair_b_[p] >= n_tri_ || pair_law_[p] < 0 ||
                pair_law_[p] >= static_cast<int>(laws_.size()))
                throw StateError("contact: pair index out of range");
        for (int t : items_)
            if (t < 0 || t >= n_tri_) throw StateError("contact: item index out of range");
        set_pair_nodes();
    }
    io.vec_sized(near_law_, 3 * static_cast<std::size_t>(n_tri_), "faces near a candidate partner");
    io.pod(energy_normal_), io.pod(energy_tangential_), io.pod(dissipation_), io.pod(damping_);
    io.pod(beta_), io.pod(energy_current_), io.pod(opt_.compute_energy);
    io.pod(damping_next_);  // (dashpot_dt_ is 0 between steps: finish_step has run; inelastic_ comes from the laws)
    io.pod(stats_.detections), io.pod(stats_.candidate_pairs), io.pod(stats_.active_pairs), io.pod(stats_.pair_evaluations);
    if constexpr (load) {
        // Per-step scratch sized as detect() leaves it.
        const std::size_t np = pair_a_.size();
        pair_f_.assign(12 * np, 0.0);
        pair_e_.assign(4 * np, 0.0);
        pair_on_.assign(np, 0);
        box_.assign(8 * static_cast<std::size_t>(n_tri_), 0.0);
        geom_.resize(static_cast<std::size_t>(n_tri_));
        faces_dirty_ = true;
    }
}

}  // namespace fdem::contact
