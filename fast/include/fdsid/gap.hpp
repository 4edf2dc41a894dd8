#pragma once
/// Sim-to-real gap diagnosis (CONTRACTS.md, `fdsid gap`): where a simulation
/// model and a periodic measurement disagree in frequency, which unmodelled
/// effect explains it, and how far the gap shrinks once that effect is added.
///
/// The noise floor is Pintelon (2002)'s non-parametric noise model (Section
/// 4.1, Eq. 25): the sample mean and variance over the M periods. Per DFT line
/// k the per-period residual E_l(k) = Y_l(k) − G(k) U_l(k) (Eq. 4 scaling) has
/// sample mean Ē(k) and sample variance s²(k), and
///   t(k) = M |Ē(k)|² / s²(k)  ~  F(2, 2M − 2)   when the model is right
/// (circular complex Gaussian noise, independent over periods: 2M|Ē|²/σ² is
/// χ²₂ and 2(M−1)s²/σ² is χ²_{2M−2}, independent). Its mean is (M−1)/(M−2),
/// so the gap is
///   gap = (M − 2)/(M − 1) · mean over the excited lines of t(k),
/// which is 1 in expectation for a right model, whatever M ≥ 4.
///
/// Tests (all stated levels are options):
///  - the gap on the excited lines: Fisher's combination −2 Σ ln p(k) ~ χ²_{2K}
///    of the per-line p-values p(k) = (1 + t/(M−1))^{−(M−1)} (the exact survival
///    function of F(2, 2M−2));
///  - nonlinearity: the same on the unexcited lines inside the excited band
///    (a random-odd multisine leaves them empty; a linear system keeps them so);
///  - leakage: period l against the mean of the later ones, d = E_l − Ē_{>l}
///    on every line — model errors are periodic and cancel in d, so this test
///    sees only what changes between periods; d is fitted by a free response
///    of the model (C (zI − A_d)⁻¹ z Δx, A_d = A or e^{A Ts}) and the F ratio
///    of that fit is judged against the same ratio of the later periods (a
///    test of the deviation's shape, not its size: noise whose power varies
///    from period to period is no transient; see leakage_p in gap.cpp);
///  - linear effects: each admitted by a quasi-likelihood F-test
///    F = ((V₀ − V₁)/q) / (V₁/(2K − q_total)) ~ F(q, 2K − q_total) (V the
///    variance-weighted residual sum, q the effect's real parameters), which
///    compares the reduction with the misfit that remains rather than with the
///    noise alone (for unmodelled_mode and mode_mismatch corrected by Šidák,
///    1 − (1 − p)^N, for the N frequencies or model modes searched), and by a
///    relevance rule (it must remove a stated share of
///    the current excess gap − 1).
/// Selection: forward, every stage refitted jointly from the model as given
/// and admitted by its effect's test on that joint fit; no stage may raise the
/// gap by more than 3 null standard deviations of it; among admissible
/// additions the lowest Schwarz criterion wins (a richer effect pays for its
/// parameters). A low-pass that would be the verdict alone gives way to a
/// lagging delay (τ > 0) admitted alone beside which it is not significant
/// (its F-test at effect_alpha): the two lags stand in for one another, and
/// the criterion's penalty is weaker than that test. The chosen set never
/// leaves more than the best effect admitted alone by more than those 3 sd. A
/// transient proven on the model as given (the transient test rejects at
/// effect_alpha) leads: its periods are dropped
/// first and the other effects selected on the steady-state periods, without
/// the 3 sd rule for that step (the transient's scatter hides misfit in the
/// noise floor; gap_model_used). Verdict: no_gap, explained (what remains
/// passes the gap test at alpha) or unexplained (see GapVerdict).
/// Bands: Benjamini–Hochberg at a stated false-discovery rate over the
/// per-line p-values of the model as given; flagged excited lines within two
/// excited lines of each other form one band (windows of 8 lines when no single
/// line is flagged).
#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "fdsid/frf_id.hpp"
#include "fdsid/model.hpp"

namespace fdsid {

struct GapOptions {
  double alpha = 0.01;         ///< level of each detection test (gap, nonlinearity, leakage)
  double effect_alpha = 1e-3;  ///< level of the F-test admitting a linear effect, of the transient test admitting leakage, and of the nonlinearity's test where it is added beside an effect found
  double min_share = 0.25;     ///< share of the current excess gap an admitted effect must remove
  double fdr = 0.05;           ///< Benjamini–Hochberg false-discovery rate of the bands
};

/// The unmodelled effects of CONTRACTS.md's table, in its order.
enum class Effect { GainError, Delay, SensorDynamics, UnmodelledMode, ModeMismatch, Nonlinearity, Leakage };

/// The one list of all effects, in CONTRACTS.md's order (the order candidates
/// are tried in and gap-validate's schedule walks).
inline constexpr std::array<Effect, 7> kAllEffects = {Effect::GainError,      Effect::Delay,
                                                      Effect::SensorDynamics, Effect::UnmodelledMode,
                                                      Effect::ModeMismatch,   Effect::Nonlinearity,
                                                      Effect::Leakage};

/// The CONTRACTS.md name: "gain_error", "delay", "sensor_dynamics",
/// "unmodelled_mode", "mode_mismatch", "nonlinearity", "leakage".
const char* to_string(Effect effect);

/// Inverse of to_string. Throws Error(Input) naming the known effects for any
/// other name.
Effect effect_from_string(std::string_view name);

/// Whether the effect is a change of the linear response G (the first five):
/// those are fitted into G; nonlinearity and leakage have their own tests.
constexpr bool is_linear(Effect e) { return e != Effect::Nonlinearity && e != Effect::Leakage; }

/// Parameters of each effect as the diagnosis fits them (see the fits in
/// gap.cpp for the forms). The JSON "parameters" object lists them under the
/// names given beside each field.

/// A resonance: natural frequency (Hz; cycles/sample when Ts = 1) and damping ratio.
struct Resonance {
  double frequency_hz = 0;  ///< "frequency_hz"
  double damping = 0;       ///< "damping"
};
/// G → g G.
struct GainError {
  double gain = 1;  ///< "gain"
};
/// G → e^{−j2πfτ} G.
struct Delay {
  double samples = 0;  ///< "samples" (τ)
  double seconds = 0;  ///< "seconds" (τ Ts)
};
/// G → L(f) G, L a unit-DC-gain low-pass of first or second order.
struct SensorDynamics {
  double cutoff_hz = 0;  ///< "cutoff_hz"
  int order = 1;         ///< "order" (1 or 2)
  bool discrete = true;  ///< "discrete" (1: the discrete form, 0: the continuous one)
  double damping = 0;    ///< "damping", listed for order 2 only
};
/// A resonance the model lacks, in parallel (G + mode) or in series (G · mode).
struct UnmodelledMode {
  std::optional<Resonance> mode;  ///< absent when no start gave a finite fit
  bool series = false;            ///< "series" (1 or 0)
};
/// One of the model's resonances moved.
struct ModeMismatch {
  std::optional<Resonance> mode;             ///< the refitted resonance; absent when none converged
  std::optional<double> model_frequency_hz;  ///< "model_frequency_hz" of the moved mode; absent when the model has none to move
};
/// Nonlinear distortion as a polynomial: static a₂ x² + a₃ x³ at the output
/// (x = G u) or at the input (x = u), or in the loop, the measured output fed
/// back through the model: y = G (u − a₁ y − a₂ y² − a₃ y³).
struct Nonlinearity {
  bool fitted = false;    ///< false: no signal to form x², x³ from (nothing listed)
  double a2 = 0, a3 = 0;  ///< "a2", "a3"
  bool at_input = false;  ///< "at_input" (1 or 0)
  bool in_loop = false;   ///< "in_loop" (1 or 0)
  double a1 = 0;          ///< "a1", listed for the in-loop form only
};
/// The first periods carry a transient and are dropped.
struct Leakage {
  int transient_periods = 0;  ///< "transient_periods"
};

/// One alternative per effect, in the order of Effect (index() is the effect).
using EffectParameters =
    std::variant<GainError, Delay, SensorDynamics, UnmodelledMode, ModeMismatch, Nonlinearity, Leakage>;

/// The parameters as (name, value) pairs, sorted by name — the JSON
/// "parameters" object and the text report list them so.
std::vector<std::pair<std::string, double>> parameter_list(const EffectParameters& parameters);

/// One effect fitted to the data alone (added to the model as given) or as
/// part of the chosen set.
struct EffectFit {
  double gap_after = 0;         ///< gap with this effect added
  double shrink = 0;            ///< 1 − gap_after / gap_before
  int dof = 0;                  ///< real parameters it adds
  double p_value = 1;           ///< its test (see the file comment)
  EffectParameters parameters;  ///< e.g. Delay{1.5, 1.5} for a delay
  Effect effect() const { return static_cast<Effect>(parameters.index()); }
};

/// One stage of the selection path: the effect added, the set after the
/// stage (an exchange may have replaced an earlier member), the gap it leaves
/// (fitted jointly) and the p-value of the test that admitted the addition.
struct SelectionStep {
  Effect added = Effect::GainError;
  std::vector<Effect> set;
  double gap_after = 0;
  double p_value = 1;
};

/// The three honest outcomes of a diagnosis (issue 17).
enum class GapVerdict {
  NoGap,        ///< "no_gap": the gap test does not reject and no effect is admitted
  Explained,    ///< "explained": effects admitted, and what remains passes the gap test
  Unexplained,  ///< "unexplained": a significant gap that the admitted effects (if any) do not fully explain
};
const char* to_string(GapVerdict verdict);

/// The best-linear-approximation view (Pintelon and Schoukens): a nonlinear
/// system driven by a random (odd) multisine acts on the excited lines as its
/// best linear approximation G_BLA plus a stochastic nonlinear distortion
/// Y_s(k), periodic (the same in every period, so it is part of the gap) and of
/// the same level on the excited lines as on the unexcited detection lines
/// beside them. There only the distortion and the noise remain, so the gap on
/// the detection lines is the gap a model that is right as a BLA would leave
/// on the excited ones: with Ē = Y_s + N̄, t = M|Ē|²/s² is noncentral
/// F(2, 2M−2) with mean (M−1)/(M−2)·(1 + M|Y_s|²/σ²), so gap − 1 is the
/// distortion power against the noise power of the M-period mean.
struct GapDistortion {
  /// Detection lines: the unexcited lines inside the excited band, only the
  /// odd ones when every excited line is odd (even-order distortion falls on
  /// even lines, never on odd excited ones). Fewer than 4: not estimable.
  bool estimable = false;
  bool odd_only = false;
  int lines = 0;
  double gap = 1;                ///< the gap on the detection lines (model as given)
  std::optional<double> level_db;  ///< 10 log10(gap − 1): distortion over the noise of the mean; absent when gap ≤ 1
  double share = 0;              ///< (gap − 1) / (gap_before − 1): the share of the excess gap it accounts for
  double p_detected = 1;         ///< Fisher's combination over the detection lines (distortion present?)
  /// Is the excited lines' gap larger than the distortion predicts? Each
  /// excited line's t against the mean t of its 4 nearest detection lines
  /// (the distortion level changes with frequency), the sums' standardised
  /// difference Z against its null law by Monte Carlo (every t an independent
  /// F(2, 2M−2) variate at one level; 2000 draws, fixed seed, p ≥ 1/2001);
  /// one-sided.
  double p_beyond = 1;
  /// The smallest p_beyond the Monte Carlo can give, 1/2001 (none of its
  /// draws reached the statistic); 0 when the normal tail was used.
  double p_beyond_min = 0;
  /// The gap is significant, the distortion is detected, and the excited
  /// lines show no more than it (p_beyond ≥ alpha): the model is right as a
  /// best linear approximation and the gap is nonlinear distortion.
  bool bla_right = false;
};

struct GapReport {
  double gap_before = 0, gap_after = 0;
  GapVerdict verdict = GapVerdict::NoGap;
  /// The gap test (Fisher's combination over the excited lines) on what
  /// remains after the present effects; p_gap when none is present.
  double p_after = 1;
  /// The other tail of the same statistic: the chance that noise alone, less
  /// the q real parameters the present effects fitted, leaves a gap as small
  /// as gap_after (Fisher's X against χ² with 2K − q degrees of freedom, K
  /// excited lines); 1 when none is present. Below the level, the effects
  /// fit part of the noise too: more flexible than the data support (the
  /// verdict line of an explained gap says so).
  double p_below = 1;
  /// Share of the excess gap the present effects remove:
  /// (g − gap_after) / (g − 1) with g = max(gap_before, gap_model_used); 0
  /// when none is present.
  double explained_share = 0;
  /// The model as given on the periods gap_after is measured on (the last
  /// periods_used): gap_before when no transient period was dropped. A
  /// transient's period-to-period scatter inflates the noise floor, so this
  /// can exceed gap_before: the misfit the transient hid.
  double gap_model_used = 0;
  /// The forward selection's stages, in order (empty when none was admitted).
  std::vector<SelectionStep> path;
  std::vector<Effect> present;                     ///< judged present, largest shrink first
  std::vector<std::array<double, 2>> bands;        ///< Hz (cycles/sample when Ts = 1)
  /// Where the gap concentrates inside the bands: the fewest flagged lines
  /// whose excess t(k) − 1 holds half the excess gap Σ_k (t(k) − 1) of the
  /// model as given (all flagged lines when they hold less), merged into
  /// intervals as the bands are (lines at most 2 excited lines apart), each
  /// with its share of the excess; largest share first. Half, a median of
  /// the excess over frequency: a description, no test.
  struct Peak {
    std::array<double, 2> band;  ///< Hz
    double share = 0;            ///< of the whole excess gap
  };
  std::vector<Peak> peaks;
  std::vector<EffectFit> candidates;               ///< every effect tried alone, best first
  std::vector<EffectFit> chosen;                   ///< the present ones, as fitted jointly (greedy order)
  /// When one linear effect e is present: the other linear effects g that
  /// explain the record as well — g alone passed its own test, its Schwarz
  /// criterion is within 1 of e's (2 ln B ≤ 2), and adding e to g is not
  /// significant (F-test at effect_alpha), so the data cannot tell e from g
  /// (a delay and a high-cut-off low-pass, say). With the p-value of adding
  /// e to g.
  std::vector<std::pair<Effect, double>> alternatives;
  /// When one linear effect e is present: pairs g, h of other linear
  /// effects, each admitted alone, that jointly explain the record as well —
  /// each passes an addition's test beside the other alone (F-test at
  /// effect_alpha, relevance, gap rule) and the pair's Schwarz criterion is
  /// within 1 of e's either way (2 ln B ≤ 2). Where it is lower by more, the
  /// pair is the verdict instead (ForwardSelection::pair_beats_single).
  std::vector<std::array<Effect, 2>> alternative_pairs;
  /// When one linear effect e is present: the linear effects g that, fitted
  /// jointly beside e, explain the record as well as e alone — the pair's
  /// Schwarz criterion within 1 of e's (2 ln B ≤ 2) — and adding g is not
  /// significant (F-test at effect_alpha): the record cannot tell whether g is
  /// there too (a delay beside a low-pass is close to a low-pass of another
  /// shape). With the p-value of adding g to e. Only with the verdict
  /// "explained": where a gap remains nothing explains the record as well.
  std::vector<std::pair<Effect, double>> possible_additions;
  /// The chosen mode effects (unmodelled_mode, mode_mismatch) whose fit sits
  /// at a bound of its search or, for a moved mode, outside the excited band:
  /// stand-ins, not resonances the data resolve (a note each says why).
  std::vector<Effect> stand_ins;
  int periods_used = 0;                            ///< M after dropping transient periods
  int excited = 0, unexcited = 0;                  ///< lines in each test
  double p_gap = 1, p_nonlinearity = 1, p_leakage = 1;  ///< detection tests on the model as given
  /// The nonlinearity's prediction test (the polynomial fitted on the excited
  /// lines against the unexcited lines' mean residual; gap.cpp,
  /// Diagnosis::nonlinearity_prediction_p) on the periods the selection starts
  /// from (after a leading transient's). It admits a nonlinearity the test
  /// above does not, at the first stage only and only where its fit beats
  /// every linear effect's (a note says so). 1 with < 4 unexcited lines.
  double p_nonlinearity_prediction = 1;
  /// Whether the periods after the first carry the same noise power
  /// (period_power_test below, on lines 1 … P/2): the tests above are
  /// derived for equal power and stay valid, if conservative, without it (a
  /// line's t is then Student's t under unequal variances; the reasoning and
  /// the measurements at period_power in gap.cpp), except a static model's
  /// transient test, a test of size. p < effect_alpha adds a note that says
  /// so. Relative power per period, the
  /// first and any further periods a detected transient reaches left out
  /// (the leakage test's); empty (and p = 1) with < 3 periods left or < 30
  /// line pairs carrying noise (period_power_test).
  double p_period_power = 1;
  std::vector<double> period_power;
  /// Whether the noise is independent from period to period
  /// (period_independence_test below, same periods and lines): the mean
  /// circular lag-1 correlation of the period deviations and its null mean.
  /// p < effect_alpha adds a note: the periods' scatter then underestimates
  /// the noise of their mean and the p-values here come out too small.
  double p_period_independence = 1;
  double period_correlation = 0, period_correlation_expected = 0;
  GapDistortion distortion;                        ///< the best-linear-approximation view (model as given)
  GapOptions options;
  /// Plot-ready table over the excited lines: frequency (Hz), t(k) of the model
  /// as given and with every present effect added, and the per-line flag.
  Eigen::VectorXd frequency, t_before, t_after;
  std::vector<bool> flagged;
  /// t(k) on the excited lines after each stage of the augmentation, in the
  /// order the stages were added: {"model", t_before}, then e.g.
  /// {"+ leakage", …}, {"+ leakage + nonlinearity", …}, {"… + gain_error", …}.
  /// The last equals t_after. For the figure of `fdsid gap --plot`.
  std::vector<std::pair<std::string, Eigen::VectorXd>> steps;
  std::vector<std::string> notes;
  /// The decision on p_period_power: unequal noise power per period when
  /// p < effect_alpha; the report then carries the note, gap-validate counts
  /// the case as noted.
  bool period_power_unequal() const { return p_period_power < options.effect_alpha; }
  /// The decision on p_period_independence (adjacent periods alike).
  bool periods_dependent() const { return p_period_independence < options.effect_alpha; }
};

/// Equal noise power in every period (issue 17: real noise is not
/// stationary; "say that the periods disagree for another reason").
/// `residuals`: R × K, row m the residual spectrum Y_m(k) − G(k) U_m(k) of
/// period m at K consecutive DFT lines (column j: line k₀ + j).
/// Lines are first differenced in disjoint adjacent pairs, e_m(j) =
/// r_m(2j) − r_m(2j+1): the DFT of one period of coloured noise (or of the
/// response to input noise) carries, besides H(k)E_m(k), a leakage term
/// T_m(z_k)/A(z_k) set by the filter's state at the period's ends — one
/// random value per period, smooth in k and common to all lines, so the lines
/// are far from independent where it dominates (below the noise's spectral
/// peaks: a generated effect-free case with 46 dB of noise-spectrum range gave
/// p 1.7e-8 undifferenced, 0.77 differenced). The difference of adjacent
/// lines cancels it to first order; disjoint pairs keep the pairs independent.
/// Per pair the deviations d_m = e_m − ē over the R periods give shares
/// q_m(j) = |d_m|² / Σ_m |d_m|², which a periodic model error, the line's
/// noise level and a common scale leave alone; with noise of equal power,
/// independent from period to period, q(j) is exchangeable, so E q_m = 1/R
/// and Cov(q) = v R/(R−1) (I − 11ᵀ/R), v = Var q_m. Q_m, the mean of q_m
/// over the J independent pairs, is then normal for large J with covariance
/// Cov(q)/J, whose pseudo-inverse gives
///   S = J (R−1) / (v R) · Σ_m (Q_m − 1/R)²  ~  χ²(R − 1),
/// v estimated by the mean of (q_m(j) − 1/R)² over all m, j (exact under the
/// null; under unequal power it only grows, so the test errs to the safe
/// side). Only J ≥ 30 pairs and R ≥ 3 periods are tested (p = 1 otherwise):
/// the normal limit needs many pairs, and two periods have q ≡ 1/2.
/// relative[m] = R Q_m: 1 each under the null.
struct PeriodPowerTest {
  double p = 1;
  std::vector<double> relative;
};
PeriodPowerTest period_power_test(const Eigen::MatrixXcd& residuals);

/// Independent noise from period to period (issue 17: "say that the periods
/// disagree for another reason"). Every test here takes the scatter of the
/// periods about their mean as the noise floor of that mean; a disturbance
/// that varies slowly from period to period — neither periodic nor
/// independent (a hum drifting in phase, a non-periodic response) — makes
/// adjacent periods alike, so the scatter underestimates the noise of the
/// mean and t comes out too large. `residuals` as for period_power_test (R ×
/// K, consecutive lines), differenced in the same disjoint line pairs (the
/// per-period leakage term, itself correlated between adjacent periods
/// through the filter state they share, cancels).
/// Statistic: per pair j, with d_m the deviations from the periods' mean,
///   c(j) = Σ_m Re(d_m d̄_{m+1}) / Σ_m |d_m|²,  m + 1 taken modulo R
/// (circular: every period enters two products). Independent periods of
/// equal power are exchangeable and Σ_m d_m = 0, so Σ_{a≠b} d_a d̄_b = −Σ|d|²
/// and each of the R(R − 1) ordered pairs has E = −1/(R(R − 1)): E c = −1/(R − 1)
/// exactly. With unequal powers ρ_m the circular sum keeps the ratio of
/// expectations at −1/(R − 1) (each period in two products: Σ_m (1 − ρ_m −
/// ρ_{m+1})/R = −1 against Σ E|d_m|² = R − 1, for Σρ = R); the ratio's own
/// mean moves by up to 0.007 (simulated, R = 4 … 16, powers 0.25 … 3.25), so
/// the null mean is taken by Monte Carlo (kIndependenceDraws draws of R
/// independent complex normals with the relative powers `relative` of
/// period_power_test, fixed seed). Positive dependence raises c̄, the mean over
/// the J pairs; Z = (c̄ − null) / √(s²/J + s²_mc/N) (s² the pairs' sample
/// variance, s²_mc the draws') is normal for large J; p = P(N(0,1) > Z), one
/// sided (negative dependence makes the tests conservative). R ≥ 4 (with R =
/// 3 c ≡ −1/2) and J ≥ 30, else p = 1.
struct PeriodIndependenceTest {
  double p = 1;
  double correlation = 0;  ///< c̄
  double expected = 0;     ///< its null mean (≈ −1/(R − 1))
};
PeriodIndependenceTest period_independence_test(const Eigen::MatrixXcd& residuals,
                                                const std::vector<double>& relative);

/// Diagnoses the gap between `model` (SISO, discrete or continuous) and the
/// periodic record (columns u, y; P·M rows) with its meta data. Throws
/// Error(Input) for a non-SISO model or record, fewer than 4 periods, fewer
/// than 4 excited lines, or a record without period-to-period variation (no
/// noise floor: noise-free or copied periods).
GapReport diagnose_gap(const StateSpace& model, const Eigen::MatrixXd& record, int inputs, const RecordMeta& meta,
                       const GapOptions& options = {});

/// Several output channels (issue 17, item 4): a single-input record with p ≥ 2
/// outputs (u, y1, …, yp) and a model with p outputs. Each channel o is
/// diagnosed as diagnose_gap does, with the model's row o (C_o, D_o): effects
/// that are local to a channel (a sensor's delay, gain or low-pass) are found
/// in that channel's report. Combined:
///  - gap_before, gap_after: the means over the channels of theirs (each 1 in
///    expectation for a right model, so the mean is too);
///  - the joint test: per excited line the complex Hotelling statistic of the
///    p residuals over the M periods, T² = M Ēᴴ S⁻¹ Ē (S the sample covariance,
///    divisor M − 1), (M − p)/(p (M − 1)) T² ~ F(2p, 2(M − p)) for circular
///    complex Gaussian noise correlated across the outputs in any way; Fisher's
///    combination over the lines. gap_joint is the mean of those F over the
///    lines divided by their mean (M − p)/(M − p − 1): 1 in expectation.
///    Needs M ≥ p + 3 (finite F variance); fewer periods: not computed, a note;
///  - verdict: no_gap when the joint test passes and no channel has an effect
///    present; explained when every channel is explained or has no gap, one at
///    least explained, and the joint test passes or some effect is present;
///    unexplained otherwise;
///  - present: the union over the channels (channel order, then each
///    channel's order).
struct MultiGapReport {
  std::vector<GapReport> channels;
  double gap_before = 0, gap_after = 0;
  double gap_joint = 1, p_joint = 1;
  bool joint_tested = false;
  GapVerdict verdict = GapVerdict::NoGap;
  std::vector<Effect> present;
  std::vector<std::string> notes;
};

/// Throws Error(Input) as diagnose_gap does, and for several inputs (the
/// per-channel residual of several inputs needs each input's path; not
/// supported), a record whose output count differs from the model's, or a
/// single output (use diagnose_gap).
MultiGapReport diagnose_gap_outputs(const StateSpace& model, const Eigen::MatrixXd& record, int inputs,
                                    const RecordMeta& meta, const GapOptions& options = {});

/// `fdsid gap --json` for several outputs: CONTRACTS.md's fields for the
/// channels together (gap_before, gap_after: the means; present: the union;
/// bands: every channel's, merged; candidates: each effect's gap_after
/// averaged over the channels, each channel fitting its own), the verdict, the
/// joint test, and "channels": each channel's own report (gap_report_to_json)
/// with its "output" index (1-based).
nlohmann::json gap_report_to_json(const MultiGapReport& report);

/// The report as CONTRACTS.md's `fdsid gap` JSON (gap_before, gap_after,
/// present, bands, candidates) plus the tests' p-values, levels and the chosen
/// effects' joint parameters.
nlohmann::json gap_report_to_json(const GapReport& report);

/// Survival function of F(2, d2): P(F > t) = (1 + 2t/d2)^{−d2/2}.
double f2_survival(double t, int d2);

/// Standard deviation of the gap under a right model, over `lines` excited
/// lines and M = `periods` ≥ 5 periods: the gap is the mean of K independent
/// F(2, d) variates (d = 2M − 2) divided by their mean d/(d − 2), so its
/// standard deviation is √(var F(2, d)) / mean F(2, d) / √K with
/// var F(2, d) = d³ / ((d − 2)² (d − 4)). The relevance rule of the effect
/// selection is 3 of these. M = 4 (d = 6 > 4) has a finite variance too.
double gap_null_sd(int periods, int lines);

}  // namespace fdsid
