// fdem/support_velocity.cpp: support kind `velocity` (vx, vy in a [[stages.supports]] block): a prescribed velocity,
// ramped up smoothly, (1 - cos), over `ramp` from the group's prescribed velocity before the block (0 if it was fixed
// or free), times an optional time function of the time since the stage start, and, with `servo`, times a factor
// that follows the model's unbalanced-force ratio (below).
#include <algorithm>
#include <cmath>

#include "fdem/case_reader.hpp"
#include "fdem/sim_detail.hpp"
#include "fdem/support.hpp"

namespace fdem {

namespace {

class VelocitySupport final : public Support {
public:
    using Support::Support;
    double v_start = 0, v_target = 0;  // m/s
    TimeFunction fn;                   // factor on the prescribed velocity, of t - t0
    double servo_ratio = 0, servo_time = 0, servo_min = 0;  // see SupportSpec (0: no servo)
    double servo_factor = 1;  // -, the velocity factor the servo holds
    double servo_rbar = 0;    // -, the unbalanced-force ratio averaged over servo_time
    double servo_t = 0, servo_r_int = 0, servo_f_int = 0, servo_r_max = 0, servo_f_min = 1;  // stage statistics

    double ramp_end() const override { return t0 + ramp; }
    bool prescribe(double t, double dt, double& v) const override {
        // (evaluated at the half step)
        const double tau = (t + 0.5 * dt) - t0;
        v = ramp > 0 && tau < ramp ? v_start + (v_target - v_start) * 0.5 * (1 - std::cos(sim_detail::kPi * tau / ramp)) : v_target;
        if (fn.present()) v *= fn(tau);
        if (servo_ratio > 0) v *= servo_factor;
        return true;
    }
    // Servo-controlled loading rate (the Itasca codes' practice of driving a quasi-static test by its
    // unbalanced-force ratio, Itasca 3DEC manual; Lourenco, Oliveira, Roca, Orduna 2005 run their 3DEC walls so).
    // R's mean over the response time T follows rbar += w (R - rbar), w = dt / T; the factor follows
    // f <- clamp(f exp(w clamp(ln(R* / rbar), -2, 2)), f_min, 1): while the mean ratio is above the target the
    // actuator slows down (by up to e^-2 per T), below it speeds back up, never beyond the prescribed velocity.
    void after_step(double dt, double ratio) override {
        if (servo_ratio <= 0) return;
        const double w = std::min(1.0, dt / servo_time);
        servo_rbar += w * (ratio - servo_rbar);
        const double g = std::log(servo_ratio / std::max(servo_rbar, 1e-300));
        servo_factor = std::clamp(servo_factor * std::exp(w * std::clamp(g, -2.0, 2.0)), servo_min, 1.0);
        servo_t += dt;
        servo_r_int += dt * servo_rbar;
        servo_f_int += dt * servo_factor;
        servo_r_max = std::max(servo_r_max, servo_rbar);
        servo_f_min = std::min(servo_f_min, servo_factor);
    }
    std::string stage_summary() override {
        if (!(servo_ratio > 0 && servo_t > 0)) return "";
        using sim_detail::sci;
        const std::string line = "servo on '" + group + "' (" + (comp == 0 ? "vx" : "vy") + "): unbalanced-force ratio held at " +
                                 sci(servo_r_int / servo_t, 3) + " on average (largest " + sci(servo_r_max, 3) + ", target " +
                                 sci(servo_ratio, 3) + "); velocity factor " + sci(servo_f_int / servo_t, 3) + " on average, " +
                                 sci(servo_f_min, 3) + " at least";
        servo_t = servo_r_int = servo_f_int = servo_r_max = 0, servo_f_min = 1;
        return line;
    }
    template <class IO>
    void io(IO& io, int nn) {
        io_common(io, nn);
        io.pod(v_start), io.pod(v_target);
        io.str(fn.type);
        io.pod(fn.amplitude), io.pod(fn.omega), io.pod(fn.phase), io.pod(fn.offset);
        io.vec(fn.t), io.vec(fn.f);
        io.pod(servo_ratio), io.pod(servo_time), io.pod(servo_min), io.pod(servo_factor), io.pod(servo_rbar);
        io.pod(servo_t), io.pod(servo_r_int), io.pod(servo_f_int), io.pod(servo_r_max), io.pod(servo_f_min);
    }
    void save(StateWriter& w) const override { const_cast<VelocitySupport*>(this)->io(w, 0); }
    void load(StateReader& r, int nn) override { io(r, nn); }
};

class VelocityKind final : public SupportKind {
public:
    const char* key() const override { return "velocity"; }
    DofMode mode() const override { return DofMode::velocity; }
    // vx, vy (m/s), and what multiplies them: function (a time function) and servo.
    void read(case_detail::Ctx& ctx, case_detail::Reader& r, SupportSpec& s) const override {
        using case_detail::kComponents;
        using case_detail::Reader;
        for (int c = 0; c < 2; ++c) {
            const std::string key = c == 0 ? "vx" : "vy";
            if (auto v = r.number(key, false, "a velocity in m/s")) {
                if (s.mode[c] != DofMode::inherit)
                    ctx.error(r.key_path(key), r.line(), "component " + kComponents[c] + " is already fixed or freed in this support");
                s.mode[c] = DofMode::velocity;
                s.velocity[c] = *v;
            }
        }
        s.function = case_detail::read_function(ctx, r, "function");
        if (s.function.present() && s.mode[0] != DofMode::velocity && s.mode[1] != DofMode::velocity)
            ctx.error(r.key_path("function"), r.line(), "a time function multiplies a prescribed velocity: give vx or vy");
        if (const toml::table* p = r.table("servo", false, "a table { ratio = target unbalanced-force ratio, time = response time s, "
                                                           "min_factor = smallest velocity factor }")) {
            Reader sr(ctx, *p, r.key_path("servo"));
            s.servo_ratio = sr.number("ratio", true, "a target unbalanced-force ratio in (0, 1)", [](double v) { return v > 0 && v < 1; })
                                .value_or(0.0);
            s.servo_time = sr.number("time", true, "a response time > 0 in s", [](double v) { return v > 0; }).value_or(0.0);
            s.servo_min = sr.number("min_factor", false, "a smallest velocity factor in (0, 1]", [](double v) { return v > 0 && v <= 1; })
                              .value_or(0.01);
            sr.finish();
            if (s.mode[0] != DofMode::velocity && s.mode[1] != DofMode::velocity)
                ctx.error(r.key_path("servo"), r.line(), "a servo controls a prescribed velocity: give vx or vy");
        }
    }
    std::unique_ptr<Support> begin(const SupportSpec& s, int c, const SupportStart& st) const override {
        auto a = std::make_unique<VelocitySupport>(*this);
        a->fn = s.function;
        a->servo_ratio = s.servo_ratio, a->servo_time = s.servo_time, a->servo_min = s.servo_min;
        a->servo_rbar = s.servo_ratio;
        // Smooth ramp from the group's current prescribed velocity (0 if it was fixed or free).
        const int d0 = 2 * st.model.group(s.group).nodes.front() + c;
        a->v_start = st.dof_kind[d0] == 2 ? st.dof_vel[d0] : 0.0;
        a->v_target = s.velocity[c];
        return a;
    }
    std::unique_ptr<Support> restore() const override { return std::make_unique<VelocitySupport>(*this); }
};

}  // namespace

const SupportKind& velocity_support_kind() {
    static const VelocityKind kind;
    return kind;
}

}  // namespace fdem
