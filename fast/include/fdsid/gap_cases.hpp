#pragma once
/// Cases for the blind validation of the sim-to-real gap diagnosis
/// (`fdsid gap-validate`, CONTRACTS.md): a random simulation model (what the
/// user has), a periodic u,y record of a "true" system that differs from it by
/// zero, one or two withheld effects, the record's meta data, and the truth
/// (effects, frequency bands, parameters, noise level) to score against.
///
/// The case, step by step (all draws from one std::mt19937_64 seeded by
/// `seed`; the output noise has its own stream, so switching it off with the
/// testing hook `noise = false` changes nothing else):
///
/// 1. Simulation model G(z) = D + Σ_i c_i/(z − p_i) + c̄_i/(z − p̄_i) [+ r/(z − a)]:
///    2 … 4 resonances, p_i = exp(ω_i(−ζ_i + j√(1−ζ_i²))) with ω_i spread
///    (one per log-spaced slot) inside the excited band, ζ_i log-uniform on
///    [0.01, 0.2], residues of random size (peak gains within a factor 10) and
///    near-quadrature phase; a real pole with probability 1/2; D = 0 with
///    probability 1/2. Realised in real modal form (2×2 blocks), minimal, with
///    distinct poles; discrete, sample time 1.
/// 2. Excitation: random-odd multisine (Schoukens): odd lines 1 … K, K a random
///    fraction 0.15 … 0.4 of P/2; in each full group of 4 consecutive odd lines
///    one random line is left out; random phases, flat amplitude, RMS 1 exactly.
///    Even lines are never excited.
/// 3. True system: u → [input polynomial] → plant → [output polynomial] →
///    sensor low-pass → gain → delay, where the plant is the simulation model
///    with a mode moved (mode_mismatch) and/or a resonance added in parallel or
///    in series (unmodelled_mode). Every stage but the withheld ones is the
///    identity. The record is the exact periodic steady state (computed per
///    line, Y(k) = G(e^{j2πk/P}) U(k), polynomials in the time domain of one
///    period), except with `leakage`: then the experiment starts from rest
///    (zero state), and the transient of the true system is added.
/// 4. Noise: output noise v = H_v(q) e, e white Gaussian, H_v a random stable
///    first- or second-order filter normalised to mean |H_v|² = 1 over the
///    excited lines; one stationary sequence over the whole record (different
///    in every period). Its variance per line of one period's DFT
///    (Z(k) = P^{-1/2} Σ z(t) e^{−j2πkt/P}) is σ²(k) = ν |H_v(e^{j2πk/P})|².
///    With probability 1/2 a tiny white noise on the recorded input too
///    (its effect on Y/U at most 1 % of the output noise's, in variance).
///
/// Structure family (`structure = true`, issue 17 item 5; the classic draws
/// above are unchanged when it is off): the model is a lightly damped structure
/// — 5 … 8 resonances, ζ log-uniform on [0.005, 0.05], no real pole, D = 0 (a
/// strictly proper, displacement-type output, so that a nonlinearity can sit
/// in its loop); the output noise rises with frequency (H_v = 1 − a q⁻¹,
/// a ∈ [0.5, 0.95], normalised as above); and the nonlinearity is a spring in
/// the loop: the plant's input is u − f(y), f(y) = a₂ y²/r + a₃ y³/r² with y
/// the plant output (r its RMS without the loop), a Duffing-type stiffness.
/// Its periodic steady state (and its transient from rest, for leakage) comes
/// from simulating the loop sample by sample from rest until a period repeats
/// to 1e-11 of the output's peak (at most 4000 periods; a loop that does not
/// settle counts as no deviation and its magnitude is not used). Its strength
/// is the distortion on the unexcited lines, as for the static polynomial.
///
/// Continuous family (`continuous = true`, issue 17 item 5; with either family
/// above, the same draws): the simulation model is continuous-time (domain
/// "continuous", sample time 1: ω in rad/s = rad/sample) — the drawn poles
/// mapped by s = ln z (the same ω and ζ), the residues scaled so that each mode
/// keeps its peak gain |c|/|Re p| and the real pole its DC gain — and so is
/// every stage of the true system: the sensor ω_c/(s + ω_c) or
/// ω_c²/(s² + 2ζω_c s + ω_c²), the series mode (s² + 2ζ_z ω s + ω²)/(s² + 2ζ ω s + ω²),
/// a parallel mode c/(s − p) + c̄/(s − p̄), the delay e^{−jωτ}. The input is the
/// band-limited multisine of step 2 (its continuous-time signal sampled
/// exactly), so a linear chain's record is exact per line, Y(k) = G(jω_k) U(k).
/// A nonlinear stage acts on a grid 8 times finer (the input interpolated
/// exactly; harmonics of the polynomials kept at their own frequencies up to 4
/// times the sample rate) and the record samples every 8th point, as an ideal
/// sampler does; the spring in the loop's steady state there by harmonic
/// balance, Y = G(jω)(X − F[f(y)]) iterated from the linear response. Leakage's
/// transient comes from the chain's zero-order-hold discretisation on that grid
/// (the continuous chain's poles exactly; its initial state the hold's, which
/// delays the input by 1/16 sample).
///
/// Measured noise (`measured_noise`, issue 17 item 5: effects injected into
/// real measured noise; the model, excitation and effects are drawn exactly as
/// without it): the output noise is not H_v e but measured noise periods
/// (MeasuredNoise below), M of them drawn without replacement from the pool
/// by the noise stream, scaled by one factor. Its shape σ²(k)/ν = w(k) is the
/// pool's own per-line variance (mean of |N(k)|² over the pool's periods,
/// averaged over the 9 lines k−4 … k+4 — a 2·9·Q degree-of-freedom estimate for
/// Q pool periods; the measured spectrum's shape varies little over 9 lines of
/// a period-long DFT — and normalised to mean 1 over the excited lines), so the
/// calibration below holds in the mean over periods; what the measured noise
/// adds is what a Gaussian stationary model leaves out: power that varies from
/// period to period, drift, non-Gaussian bursts. The period P is the noise's.
///
/// Strength calibration. For each withheld effect alone (applied to the
/// simulation model), ratio = mean over its lines of |ΔY(k)|² / (σ²(k)/M),
/// ΔY the noise-free deviation of the output spectrum (per-period DFT as above):
///  - linear effects: ΔY(k) = (G_true(k) − G_sim(k)) U(k) at the excited lines;
///  - nonlinearity: ΔY(k) = Y(k) at the non-excited lines 1 … K (the distortion);
///  - leakage: ΔY(k) = the first period's transient, at every line 1 … K, and
///    divided by σ²(k) (one period, not the mean of M);
///  - the continuous family's sensor: ΔY(k) = (G_true(k) − G_sim(k) e^{−jω_k τ}) U(k)
///    with τ ∈ [0, 2π/ω_edge] the delay that minimises the ratio (a grid of 64
///    and Brent's method): only the part of its deviation that no delay
///    explains. A continuous low-pass far above the band is a delay there
///    (phase −ω/ω_c, gain 1 − O((ω/ω_c)²)), and calibrating its whole
///    deviation put clear sensors' cut-offs at 0.6 … 5 cycles/sample, where the
///    record cannot tell them from a delay (stop 39: 70 of 92 wrong continuous
///    verdicts). A discrete low-pass there is a fast pole, not a delay, and is
///    calibrated as the other linear effects. The truth's details give τ
///    ("delay_equivalent") and the ratio without it ("ratio_undelayed").
/// A target ratio is drawn log-uniformly from gap_ratio_range(strength); the
/// effect's physical parameters are drawn from a per-strength range, the noise
/// level ν is set to make that draw hit the target (for two effects: the
/// geometric mean) within an output SNR of 20 … 60 dB (signal power over noise
/// power at the excited lines, per period), and then each effect's magnitude is
/// rescaled by bisection to hit its target exactly. When an effect cannot reach
/// its target within its physical bounds (leakage never grows beyond "from
/// rest") the noise is lowered instead, if need be beyond the 60 dB end
/// (then truth["snr_clamped"] is true). Achieved ratios are in the truth.
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "fdsid/frf_id.hpp"
#include "fdsid/gap.hpp"
#include "fdsid/model.hpp"
#include "fdsid/names.hpp"

namespace fdsid {

enum class Strength { None, Subtle, Clear };

/// The generators' families (above): Classic and Structure each one kind of
/// case; Mixed (gap-validate) alternates them in blocks of 20 cases.
enum class GapFamily { Classic, Structure, Mixed };

/// "classic", "structure", "mixed" (gap-validate --family, the truth's "family").
const NameTable<GapFamily>& gap_family_names();
const char* to_string(GapFamily family);

/// Noise periods cut from a measured periodic record (see above), y_m the
/// record's m-th period of one column: each group of four consecutive periods
/// gives two, (y_0 − y_1 − y_2 + y_3)/2 and (−y_0 + 3y_1 − 3y_2 + y_3)/√20 (the
/// quadratic and cubic orthogonal polynomials over the group), three periods
/// left over give one, (y_0 − 2y_1 + y_2)/√6; fewer are left unused. The
/// coefficients of each are orthogonal to a constant and to a linear trend
/// over the group and the two of a group to each other, each of unit norm.
/// So the periodic response (linear and nonlinear alike) cancels exactly, and
/// so does a response that drifts linearly from period to period; noise that
/// is independent and identically distributed over the group keeps its
/// spectrum, and for Gaussian noise the noise periods are independent (an
/// orthonormal transform), within a group and across disjoint groups.
/// Differences of two periods, used before, leave such a drift in every noise
/// period with one sign: a periodic component the cases then carry on every
/// line, which the F-16 GVT's Level 1 record has (its pair differences on the
/// lines 308-1299, outside its excitation: Fisher p 3.5e-4 for a common part,
/// against 0.15-0.998 with the pairs' signs flipped) and which the diagnosis
/// rightly read as a periodic response on the unexcited lines of effect-free
/// cases. A noise power that varies between groups stays; within a group it
/// is averaged over four periods.
struct MeasuredNoise {
  int period = 0;                             ///< P
  std::vector<std::vector<double>> periods;  ///< the pool, each P samples
  std::vector<std::string> sources;          ///< where they came from (reported in the truth)
};

/// Appends the noise periods of one measured column (P·R samples, whole
/// periods) to `pool`: 2⌊R/4⌋, one more when R mod 4 = 3. Fails: Error(Input)
/// when the length is not a whole number of periods of pool.period, fewer than
/// 3 periods, or the column is not finite.
void add_measured_noise(MeasuredNoise& pool, const Eigen::VectorXd& column, const std::string& source);

/// "none", "subtle", "clear".
const char* to_string(Strength strength);

/// The range the calibration ratio (see above) is drawn from: Subtle [0.5, 3],
/// Clear [10, 100]; None [0, 0].
std::array<double, 2> gap_ratio_range(Strength strength);

struct GapCaseOptions {
  std::vector<Effect> effects;       ///< 0, 1 or 2 distinct effects (fdsid/gap.hpp)
  Strength strength = Strength::Clear;  ///< ignored when `effects` is empty; None needs it empty
  int period = 1024;                 ///< P: even, 32 … 2^22
  int periods = 8;                   ///< M ≥ 2
  std::uint64_t seed = 1;
  bool noise = true;                 ///< testing hook: false leaves out the input and output noise (nothing else changes)
  bool structure = false;            ///< the structure family (above)
  bool continuous = false;           ///< continuous-time model and true system (above)
  /// Measured noise (above); null: the synthetic noise of step 4. Needs
  /// period == measured_noise->period and periods ≤ its pool size.
  std::shared_ptr<const MeasuredNoise> measured_noise;
};

struct GapCase {
  StateSpace sim_model;              ///< what the user has: discrete (continuous with `continuous`), sample_time 1
  Eigen::MatrixXd record;            ///< P·M rows × 2 columns (u, y)
  RecordMeta meta;                   ///< period, periods, sample_time = 1, excited_lines
  std::vector<Effect> effects;       ///< the truth, in the order given
  /// Truth: bands (cycles/sample, sorted, disjoint) holding the lines that make
  /// up half of each effect's calibration ratio (at most 4 per effect, padded by
  /// one line each side); empty for effect-free cases.
  std::vector<std::array<double, 2>> bands;
  /// Effect parameters, achieved ratios, noise level and filter, system, excitation.
  /// Fields: "strength", "seed", "period", "periods", "snr_db", "snr_clamped",
  /// "noise" {"scale" (ν), "filter" {"b", "a"} (H_v in z^-1), "input_std";
  /// with measured noise also "measured" {"sources", "pool", "chosen" (pool
  /// indices, in record order), "factor" (the samples' scale)}},
  /// "system" {"modes" [{"frequency", "damping", "residue" [re, im]}], "real_pole", "D"} (continuous: the
  /// residues and the real pole in s), "domain" ("discrete" or "continuous"),
  /// "excitation" {"band_line" (K), "lines", "rms"}, "ratio_combined" (all
  /// effects together, on the excited lines), and "details" {name: {"ratio",
  /// "target_ratio", "scale", "bands", parameters…}} per effect.
  nlohmann::json truth;
};

/// Makes one case; deterministic in options.seed. Throws Error(Input) for a
/// repeated effect, more than two effects, effects with
/// Strength::None, or a bad P / M.
GapCase make_gap_case(const GapCaseOptions& options);

}  // namespace fdsid
