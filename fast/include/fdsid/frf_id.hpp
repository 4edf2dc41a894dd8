#pragma once
/// Frequency-domain subspace identification from FRF samples and periodic
/// input/output data: Pintelon (2002), Algorithms 1 and 2 (Section 3.1), the
/// sample-subspace variant (Section 4.1), errors-in-variables and improper
/// models (Section 5), and the choice of r by V_SUB (Eq. 35).
#include <algorithm>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "fdsid/matrix_stack.hpp"
#include "fdsid/model.hpp"
#include "fdsid/names.hpp"

namespace fdsid {

/// Frequency-domain data at F distinct frequencies (Pintelon 2002, Eqs. 3, 15).
/// Each frequency k carries c "columns" (the same c for all k): column j is one
/// input/output pair U[k].col(j) ∈ C^m, Y[k].col(j) ∈ C^p with the variance of
/// each output entry (circular complex noise, independent entries).
/// Periodic input/output data: c = 1. FRF data: U[k] = I_m, Y[k] = G(ξ_k), c = m.
struct FrfData {
  Domain domain = Domain::Discrete;
  /// Discrete: carried into the identified model (ω is in rad/sample whatever
  /// the sample time), positive. Continuous: ω is in rad/s and the identified
  /// model has sample_time 0 (no sample period), whatever this says.
  double sample_time = 1.0;
  Eigen::VectorXd omega;                ///< F distinct frequencies
  ComplexMatrixStack U;      ///< F matrices m × c
  ComplexMatrixStack Y;      ///< F matrices p × c
  RealMatrixStack variance;  ///< F matrices p × c: σ²_Y of each entry of Y, > 0
  /// Whether `variance` is a noise model (known or sample variance) rather than
  /// a placeholder weight of 1 (FRF files without a G_var column). Only the
  /// automatic order selection reads it.
  bool has_noise_model = true;

  int frequencies() const { return static_cast<int>(omega.size()); }
  int inputs() const { return U.empty() ? 0 : static_cast<int>(U.rows()); }
  int outputs() const { return Y.empty() ? 0 : static_cast<int>(Y.rows()); }
  int columns() const { return U.empty() ? 0 : static_cast<int>(U.cols()); }
};

/// FRF data G(ξ_k) (p × m each) with the variance of each entry: U[k] = I_m.
/// An empty `variance` means unit weights (has_noise_model = false).
/// The matrices must share one shape (Error(Input) naming the first that does not).
FrfData frf_data(Domain domain, const Eigen::VectorXd& omega, const std::vector<Eigen::MatrixXcd>& G,
                 const std::vector<Eigen::MatrixXd>& variance = {});
/// The same from stacks, taken by value: pass them with std::move where they
/// are not needed after (a file reader fills them directly).
FrfData frf_data(Domain domain, const Eigen::VectorXd& omega, ComplexMatrixStack G, RealMatrixStack variance = {});

/// Checks shapes, finiteness, positive variances, distinct frequencies in range
/// (discrete: 0 ≤ ω ≤ π; continuous: ω > 0). Throws Error(Input) or Error(Grid)
/// naming the frequency index and the number.
void validate(const FrfData& data, const std::string& where = "data");

/// Algorithm 2's two continuous-time variants (Section 3.1).
enum class ContinuousMethod {
  Bilinear,   ///< 2.1: ξ = w = (s/ω_s − 1)/(s/ω_s + 1), then the bilinear state-space back-transformation
  Orthogonal  ///< 2.2: ξ = s/ω_s with two orthonormal polynomial bases (Forsythe/Arnoldi) and the generalised shift
};
const char* to_string(ContinuousMethod m);

/// The bases for discrete-time data (issue 15, item 4): Algorithm 1's, and
/// Algorithm 2's two on the Tustin frequencies.
enum class DiscreteMethod {
  Monomial,  ///< Algorithm 1 as printed: ξ = z = e^{jω}, rows z^0 … z^{r−1} (Eq. 7)
  /// Algorithm 2.1 on the Tustin frequencies: z = e^{jω} is mapped to
  /// s' = (z − 1)/(z + 1) = j tan(ω/2) (exact for rational G: G_d(z) =
  /// G'(s'), same order), then to w = (s'/t_s − 1)/(s'/t_s + 1) with
  /// t_s = tan(ω_s/2), and Algorithm 1 runs in w; the w-model goes back to s'
  /// (bilinear_to_continuous, scale t_s) and to z (the same map with scale 1,
  /// domain discrete: bilinear_to_discrete). The composite z ↦ w is a Möbius
  /// map of the unit circle onto itself that spreads the arc [ω_min, ω_max]
  /// over the circle as Algorithm 2.1 spreads a continuous band: the discrete
  /// counterpart of the frequency scaling, for narrow-band data on which the
  /// powers of z are numerically dependent (a band of 6.5 % of [0, π] with r =
  /// 24: min |R11_ii| / max = 8e-14). Real-coefficient Möbius maps of the
  /// circle are exactly these scalings of s', so the arc in w is fixed by the
  /// band's ratio tan(ω_max/2)/tan(ω_min/2): 1.7 rad for the F-16's 7.5, but
  /// only 0.5 rad for a ratio of 1.7 (then use Orthogonal).
  Bilinear,
  /// Algorithm 2.2 on the Tustin frequencies: orthonormal polynomial bases in
  /// s̃ = j tan(ω/2)/t_s (Forsythe/Arnoldi, weighted by the data as in 2.2),
  /// conditioned on a band of any width or ratio; the s̃-model is scaled to s'
  /// and mapped to z by tustin_to_discrete. ω = π (s' = ∞) is refused.
  Orthogonal
};
const char* to_string(DiscreteMethod m);
/// The names of the two enumerations' values (bilinear, orthogonal; monomial,
/// bilinear, orthogonal): to_string's, --method's and the cases' "method".
const NameTable<ContinuousMethod>& continuous_method_names();
const NameTable<DiscreteMethod>& discrete_method_names();

struct FrfOptions {
  int order = 0;  ///< n_a; 0 reads it from the singular values of step 1c
  int r = 0;      ///< r > n_a; 0 chooses it by minimising V_SUB (Eq. 35) over [r_min, r_max]
  int r_min = 0;  ///< 0: max(n_a + 1, ⌈1.5 n_a⌉)   (Section 5)
  int r_max = 0;  ///< 0: max(r_min, 6 n_a)         (Section 5; larger when asked)
  int max_order = 0;  ///< largest order the automatic selection considers; 0: min(20, r p − 1)
  ContinuousMethod continuous = ContinuousMethod::Bilinear;
  double omega_scale = 0;  ///< ω_s of Algorithm 2; 0: √(ω_min ω_max) (discrete bilinear: default_discrete_scale)
  DiscreteMethod discrete = DiscreteMethod::Monomial;
};

struct FrfResult {
  StateSpace model;
  int order = 0;
  int r = 0;
  /// Singular values of C_Y^{-1/2} R22ᵀ (step 1c), all r p of them, largest first.
  Eigen::VectorXd singular_values;
  /// The r used to read the order (automatic order) — equals r otherwise.
  int order_r = 0;
  double v_sub = 0;  ///< Eq. (35) at the estimate
  /// V_SUB for every r tried (empty when r was given): screened from one
  /// factorisation, identify_frf_fixed's own value at the chosen r and at any
  /// r the search recomputed (those below the chosen one, ruled out as unusable).
  std::vector<std::pair<int, double>> r_scan;
  /// The r of least V_SUB when its estimate was unusable in double precision
  /// and the search took the least V_SUB among usable ones instead (a note
  /// says so); 0 otherwise.
  int r_unusable_least_v_sub = 0;
  Eigen::VectorXcd poles;
  /// The automatic order stopped at the top of its search range (a warning says so).
  bool order_at_search_cap = false;
  /// ω_s of Algorithm 2 that was used (continuous time, rad/s; discrete time
  /// with DiscreteMethod::Bilinear, rad/sample; 0 with the monomial basis).
  double omega_scale = 0;
  /// κ = max((max(σ_1, ‖L⁻¹‖‖R‖)/σ_n of step 1c) · cond(Ô_r[1:r−1]) of step 2 ·
  /// cond(R11) of step 1b, cond of step 3's least squares): the first-order
  /// amplification of rounding errors into Â (first factor; ‖L⁻¹‖‖R‖ is the
  /// whitened size of all of Z, whose QR rounding lands in R22) and into B̂, D̂.
  double condition = 0;
  /// u · κ: a first-order estimate of the relative rounding error of Â (and
  /// the poles) on noise-free data; tests scale tolerances by it. An estimate,
  /// not a proven bound (cond(R11) was added after a narrow-band grid, n = 1,
  /// showed errors 1e6 × u with the first two factors alone).
  double error_estimate = 0;
  /// Whether the rounding's effect on Ĝ and the poles was measured (only when
  /// error_estimate exceeds kPrecisionWarningLevel: below it nothing is said).
  bool rounding_assessed = false;
  /// Similarity-invariant rounding estimates (statistical: what
  /// rounding_moves names moved by its rounding's size in random directions,
  /// the estimate recomputed): the relative error of Ĝ on the data's frequencies,
  /// ‖ΔG‖_F/‖G‖_F, and the largest relative pole error |Δλ|/|λ|; infinite
  /// when a moved estimate fails (a warning names the step).
  double g_error_estimate = 0;
  double pole_error_estimate = 0;
  /// What error_estimate bounds and what was moved for the G and pole
  /// estimates (the JSON's error_estimate_of and usable_from): the subspace
  /// estimate's here; the ML refinement's when identify-frf refines.
  std::string error_estimate_of = "A's entries in the estimate's basis (u x condition, a first-order bound)";
  std::string rounding_moves =
      "R of step 1b and C_Y of step 1c moved by their rounding in random directions, steps 1c-3 rerun";
  /// The relative error that decides whether the model is usable: the larger
  /// of the G and pole estimates when assessed, else error_estimate.
  double usability_estimate() const {
    return rounding_assessed ? std::max(g_error_estimate, pole_error_estimate) : error_estimate;
  }
  /// Plain-language warnings where fast/ may lose accuracy (error_estimate
  /// above 1e-6). Printed by the CLI and written to the JSON.
  std::vector<std::string> warnings;
  /// Plain-language notes on choices made for the user where nothing is wrong
  /// (the automatic order read at a lower r than the default). Printed by the
  /// CLI as "note:" and written to the JSON's "notes".
  std::vector<std::string> notes;
  /// Noise level of step 1c's squared singular values (Marchenko–Pastur edge of
  /// whitened noise) used by the automatic order selection; 0 when unused.
  double noise_edge = 0;
};

/// Pintelon (2002) Algorithm 1 (discrete time) or Algorithm 2 (continuous time)
/// for fixed n_a and r, p outputs, m inputs, c columns per frequency.
///
/// Method: step 1a builds the real data matrix Z = [𝐔^re; 𝐘^re] (Eqs. 9, 11,
/// 18) one frequency at a time and never stores it: step 1b is a chunked
/// Householder QR (TSQR) of Zᵀ — R of [R; next rows] — split over threads and
/// merged, which keeps memory at O(r² (m+p)²) and gives the same R as a dense
/// QR up to row signs. C_Y = Σ Re((W_r W_rᴴ) ⊗ diag σ²) (the meaning of the
/// garbled line in Eq. 18) is factored once, C_Y = L Lᵀ, and both square roots
/// of step 1c come from L. Step 2: Eq. (19) by a least-squares solve
/// (generalised shift for the orthogonal bases). Step 3: Eq. (17) with
/// W = 1/σ, a real linear least-squares problem in (B, D) (real and imaginary
/// parts stacked).
/// Numerical aspects: O(F c r² (m+p)²) flops for step 1, O(F c n³) for step 3.
/// Fails with Error(Dimension) when 2 F c < r (m + p) or r ≤ n_a, with
/// Error(Numerical) when 𝐔^re is rank deficient (input not persistently
/// exciting, Assumption 3) or I − A_w is singular in the back-transformation.
/// References: Pintelon, Automatica 38 (2002) 1295–1311; McKelvey, Akçay &
/// Ljung, IEEE TAC 41 (1996); Verhaegen (1994); Yang & Sanada (2000).
/// Discrete data with DiscreteMethod::Bilinear: see there; omega_scale is then
/// ω_s in rad/sample, 0 < ω_s < π.
/// assess_rounding: measure the rounding's effect on Ĝ and the poles when
/// error_estimate exceeds kPrecisionWarningLevel (FrfResult::rounding_assessed;
/// 3 more runs of steps 1c-3); false for inner loops that read only the model
/// (Monte Carlo studies, the gap's start values).
FrfResult identify_frf_fixed(const FrfData& data, int order, int r,
                             ContinuousMethod continuous = ContinuousMethod::Bilinear, double omega_scale = 0,
                             DiscreteMethod discrete = DiscreteMethod::Monomial, bool assess_rounding = true);

/// identify_frf_fixed for several noise models of the same measurements:
/// data[v] differ only in `variance` (U, Y, ω, domain and sample time must be
/// equal; Error(Input) otherwise). Step 1b's QR of Zᵀ does not involve the
/// variances, so it is computed once; C_Y, the SVD of step 1c, steps 2 and 3
/// run per noise model. Result v is bit for bit identify_frf_fixed(data[v], …)
/// (Pintelon 2002 Section 6.1 compares the sample-variance and the
/// known-variance estimates of one run this way).
std::vector<FrfResult> identify_frf_fixed(const std::vector<FrfData>& data, int order, int r,
                                          ContinuousMethod continuous = ContinuousMethod::Bilinear,
                                          double omega_scale = 0, DiscreteMethod discrete = DiscreteMethod::Monomial,
                                          bool assess_rounding = true);

/// Identification with the choices of Section 5: the order from the singular
/// values of step 1c (when options.order == 0) and r minimising V_SUB (Eq. 35)
/// over [1.5 n_a, 6 n_a] (when options.r == 0). The order rule: with a noise
/// model, whitened noise gives squared singular values ≈ 1 (C_Y is the
/// covariance of 𝐍^re), so n_a counts those above (1 + √(r p / (2 F c)))²
/// (the Marchenko–Pastur edge) times 2; without one, the largest ratio
/// σ_n / σ_{n+1}. The r search screens every r from one QR of Zᵀ at the
/// top of the range (each r's R re-triangularised from its leading block; the
/// screened V_SUB equal identify_frf_fixed's to rounding) and recomputes the
/// least as identify_frf_fixed does: the returned estimate is
/// identify_frf_fixed's at the chosen r, bit for bit.
FrfResult identify_frf(const FrfData& data, const FrfOptions& options = {});

/// Step 1 only: the singular values of C_Y^{-1/2} R22ᵀ for a given r.
Eigen::VectorXd frf_singular_values(const FrfData& data, int r,
                                    ContinuousMethod continuous = ContinuousMethod::Bilinear,
                                    double omega_scale = 0, DiscreteMethod discrete = DiscreteMethod::Monomial);

/// The default ω_s (rad/sample) of DiscreteMethod::Bilinear: 2 atan √(t_lo t_hi)
/// with t = tan(ω/2) at the lowest and highest frequency strictly inside
/// (0, π) — the discrete counterpart of Algorithm 2's √(ω_min ω_max): the
/// band's edges land symmetrically about w = −j. π/2 (t_s = 1, the plain
/// Tustin map) when no frequency lies inside (0, π).
double default_discrete_scale(const Eigen::VectorXd& omega);

/// Step 3 alone (Eq. 17 with W = 1/σ): B and D for given A and C, with
/// ξ = e^{jω} (discrete) or ξ = jω (continuous; A in rad/s). Used for the
/// paper's "α known" estimate β̂(α₀) (Section 6.1) and by the gap diagnosis.
StateSpace fit_input_matrices(const FrfData& data, const Eigen::MatrixXd& A, const Eigen::MatrixXd& C);

/// G at frequency ω: z = e^{jω} (discrete, ω in rad/sample) or s = jω (continuous).
Eigen::MatrixXcd frequency_response(const StateSpace& model, double omega);

/// G at many frequencies at once: C(ξI − A)⁻¹ by the eigenvectors of A when
/// their basis is well conditioned (κ₁(V) ≤ 100, error ≤ κ u relative to a
/// backward-stable solve), else by one LU per frequency. A frequency on a
/// pole gives Inf entries.
std::vector<Eigen::MatrixXcd> frequency_response(const StateSpace& model, const Eigen::VectorXd& omega);

/// One entry G_{output,input}(ω_k) at every ω_k, the same values as the
/// matrices above, into one vector (a Monte Carlo loop's SISO curves, without
/// F small matrices per call).
Eigen::VectorXcd frequency_response(const StateSpace& model, const Eigen::VectorXd& omega, int output, int input);

/// The warning for an unstable model, or "": a pole of modulus >= 1
/// (discrete) or real part >= 0 (continuous); the worst one is named.
std::string instability_warning(Domain domain, const Eigen::VectorXcd& poles);

/// Eq. (35): Σ_k Σ_j Σ_i |Y − G U|²_i / σ²_i over all frequencies and columns.
double v_sub(const StateSpace& model, const FrfData& data);
/// V_SUB's T = F p c terms |Y − G U|²_i / σ²_i one by one (frequency by
/// frequency, each p × c block column-major): Exp(1) at the true model with
/// known variances, F(2, 2M − 2) with the sample variances of M periods.
Eigen::VectorXd v_sub_terms(const StateSpace& model, const FrfData& data);

/// Bilinear back-transformation of Algorithm 2.1: (A_w, B_w, C_w, D_w) in
/// w = (s/ω_s − 1)/(s/ω_s + 1) to (A, B, C, D) in s:
/// A = ω_s (I − A_w)⁻¹(I + A_w), B = √2 ω_s (I − A_w)⁻¹ B_w,
/// C = √2 C_w (I − A_w)⁻¹, D = D_w + C_w (I − A_w)⁻¹ B_w.
/// Derivation: wI − A_w = [s̃(I − A_w) − (I + A_w)]/(s̃ + 1) and
/// (s̃ + 1)(s̃I − A_c)⁻¹ = I + (I + A_c)(s̃I − A_c)⁻¹ with I + A_c = 2(I − A_w)⁻¹.
/// Throws Error(Numerical) when I − A_w is singular (a pole at s = ∞).
StateSpace bilinear_to_continuous(const StateSpace& w_model, double omega_scale);

/// The inverse Tustin map: (A', B', C', D') in s' to (A, B, C, D) in z, where
/// s' = (z − 1)/(z + 1), i.e. z = (1 + s')/(1 − s'): the formulas of
/// bilinear_to_continuous with scale 1 (s'I − A' = (I − A')(zI − A_z)/(z + 1),
/// A_z = (I − A')⁻¹(I + A'), and so on as there); domain discrete, sample_time
/// 1 (the caller sets it). Throws Error(Numerical) when I − A' is singular (a
/// pole at z = ∞).
StateSpace tustin_to_discrete(const StateSpace& s_model);

/// DiscreteMethod::Bilinear's back-transformation: (A_w, B_w, C_w, D_w) in w to
/// (A, B, C, D) in z = e^{jω}: s' = t_s (1 + w)/(1 − w) (bilinear_to_continuous
/// with scale t_s = tan(ω_s/2)), then tustin_to_discrete. Throws
/// Error(Numerical) when I − A_w is singular (a pole at z = −1) or I − A' is.
StateSpace bilinear_to_discrete(const StateSpace& w_model, double omega_scale);

// ---------------------------------------------------------------------------
// Periodic records and sample statistics (Section 4.1, Section 5)

/// Meta data of a periodic record (CONTRACTS.md).
struct RecordMeta {
  int period = 0;      ///< P samples per period
  int periods = 0;     ///< M
  double sample_time = 1.0;
  std::vector<int> excited_lines;  ///< DFT lines 1 … P/2 driven by the excitation
};

/// Eq. (4): DFT Z(k) = (1/√P) Σ_t z(t) e^{−j2πkt/P} of each of the M periods
/// of each channel (samples: P·M rows, one column per channel), at `lines`.
/// Returns [l][k] = vector over channels. FFTW r2c, one plan per call.
std::vector<std::vector<Eigen::VectorXcd>> period_spectra(const Eigen::MatrixXd& samples, int period, int periods,
                                                          const std::vector<int>& lines);

/// Sample statistics over M ≥ 2 experiments: Eq. (25) for Ŷ, σ̂²_Y (and the
/// same for U), Eq. (32) for σ̂_YU. `data` holds Û, Ŷ and σ̂²_Y / M (Section
/// 4.1: the sample-subspace algorithm replaces Y, σ²_Y by Ŷ, σ̂²_Y/M).
struct SampleStatistics {
  FrfData data;
  RealMatrixStack var_U;      ///< σ̂²_U per line k (var_U[k]: m × 1, one entry per input; 1/(M−1) form, not divided by M)
  ComplexMatrixStack cov_YU;  ///< σ̂_YU(k) of Eq. (32), p × m, not divided by M
  int M = 0;
};
/// U_l[l][k] ∈ C^m, Y_l[l][k] ∈ C^p. Throws Error(Input) for M < 2.
SampleStatistics sample_statistics(Domain domain, const Eigen::VectorXd& omega,
                                   const std::vector<std::vector<Eigen::VectorXcd>>& U_l,
                                   const std::vector<std::vector<Eigen::VectorXcd>>& Y_l);

/// The listed excited lines must carry the input: throws Error(Input) on
/// "meta field \"excited_lines\"" when more than half of them are quiet — at
/// the rounding floor of the record (|Û|² ≤ 1e-20 of one period's energy) or
/// within the period-to-period noise (|Û|² / (σ̂²_U/M) below the upper 1 %
/// point of F(2, 2M−2), its law on a line without input) on every input. A
/// 0-based or shifted list of an odd multisine fails so; the right list never
/// does (each of its lines is quiet with probability ≤ 1 %). M < 2: no test.
void require_input_power(const Eigen::MatrixXd& samples, int inputs, const RecordMeta& meta);

/// The first excited line listed twice in `lines`, or -1 (record_statistics
/// and simulate-records refuse such a list).
int repeated_line(const std::vector<int>& lines);

/// The frequencies of the meta's excited lines: ω_k = 2πk/P (discrete,
/// rad/sample) or 2πk/(P Ts) (continuous, rad/s), in the meta's order.
Eigen::VectorXd line_frequencies(const RecordMeta& meta, Domain domain);

/// Periodic input/output record (inputs then outputs as columns) → sample
/// statistics at the excited lines. ω_k = 2πk/P (discrete, rad/sample) or
/// 2πk/(P Ts) (continuous, rad/s). Throws Error(Input) naming what is wrong
/// (rows ≠ P·M, no excited lines, a line outside 1 … P/2 or repeated, M < 2).
SampleStatistics record_statistics(const Eigen::MatrixXd& samples, int inputs, const RecordMeta& meta,
                                   Domain domain);

/// Records with a known output noise level (review finding 33: fewer than 4
/// periods, even one, as in many real records): Û and Ŷ the means over the
/// M ≥ 1 periods and the variance of Ŷ from the white output noise's std σ_i
/// per sample (one for all outputs, or one per output): Eq. (4)'s 1/√P keeps
/// E|V(k)|² = σ², the mean of M periods σ²/M. The known-variance estimator of
/// Pintelon (2002) Section 3 (Theorem 1: consistent for any M); the input is
/// taken as noise-free. Fails: as record_statistics (but M ≥ 1), and a
/// noise_std list of the wrong length or a value ≤ 0.
/// warnings (M ≥ 2): the given σ_i against the outputs' scatter over the
/// periods (a std given as a variance, in other units, or for another
/// sensor: the fit verdict and the refinement would weigh every residual
/// wrongly). Method: under white Gaussian noise of std σ the deviations from
/// the mean of M periods at F lines give T = 2 Σ|Y_l(k) − Ȳ(k)|²/σ² ~ χ² with
/// ν = 2 F (M − 1) degrees of freedom; a warning when T falls outside the
/// two-sided 99.9 % interval of that law (false-alarm rate 1e-3 when σ is
/// right), naming the std the scatter implies.
FrfData record_known_noise(const Eigen::MatrixXd& samples, int inputs, const RecordMeta& meta, Domain domain,
                           const std::vector<double>& noise_std, std::vector<std::string>* warnings = nullptr);

/// Section 5, errors-in-variables (SISO): U = 1, Ĝ = Ŷ/Û and variance σ̂²_G / M.
/// Eq. (31) as printed divides σ̂_YU by Ŷ Û; the first-order expansion
/// δG = G (δY/Y − δU/U) gives E[δY conj δU] / (Y conj U), so this uses
/// σ̂²_G = |Ĝ|² (σ̂²_Y/|Ŷ|² + σ̂²_U/|Û|² − 2 Re(σ̂_YU / (Ŷ conj Û))).
/// Eq. (34): lines whose input SNR |Û|² / (σ̂²_U/M) is below `min_input_snr`
/// (default 10, the paper's 10 dB region) are dropped; how many is returned in
/// `dropped`. When `first_pass` is given, the variance is evaluated at that
/// model's G₁ instead of the noisy Ĝ:
/// σ²_G = (σ̂²_Y + |G₁|² σ̂²_U − 2 Re(conj(G₁) σ̂_YU)) / (M |Û|²), which removes
/// the correlation of the weight with Ŷ. Measured (tests/frf_id_test.cpp): it
/// halves the bias of the Ĝ-based weight, but |Û|² in the denominator still
/// correlates with Ĝ = Ŷ/Û, leaving a relative bias ≈ −σ²_U/(M|U₀|²) that does
/// not vanish as F grows (−1.6e-3 at an input SNR of 600). Open.
/// The variance of Y − G U when Y and U carry noise of variances var_y, var_u
/// and covariance cov_yu = E[δY conj δU]: var_y + |G|² var_u − 2 Re(cov_yu conj G)
/// (SISO). The first-pass weight of errors_in_variables (times 1/|Û|²) and the
/// denominator of the errors-in-variables ML cost (refine.hpp).
double eiv_residual_variance(double var_y, double var_u, cplx cov_yu, cplx G);

FrfData errors_in_variables(const SampleStatistics& stats, const StateSpace* first_pass = nullptr,
                            double min_input_snr = 10.0, int* dropped = nullptr);

/// Section 5, improper models (n_b > n_a): the roles of input and output are
/// swapped — U = 1, Ĥ = Û/Ŷ with the variance of Eq. (31) with the roles of U
/// and Y exchanged (SISO), and the same line rule. The subspace algorithm then
/// identifies the proper H = 1/G; a G with n_b > n_a has no state-space form,
/// so the result is H, and the caller reports it as the inverse model.
FrfData swap_input_output(const SampleStatistics& stats, double min_input_snr = 10.0, int* dropped = nullptr);

}  // namespace fdsid
