#pragma once
/// Whole procedures of the command-line tool as library calls: the rules and
/// passes that `fdsid identify-frf`, `sample-spectrum`, `check` and
/// `reproduce fig1/fig2` apply around the algorithms, so that a program
/// embedding fast/ gets the same results as the tool (which only parses
/// options and formats output).
#include <string>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "fdsid/compare.hpp"
#include "fdsid/frf_id.hpp"
#include "fdsid/io.hpp"
#include "fdsid/model.hpp"
#include "fdsid/names.hpp"
#include "fdsid/spectrum_id.hpp"

namespace fdsid {

// ---------------------------------------------------------------------------
// Identification from FRF samples or periodic records (Pintelon 2002)

/// Purpose: refuse a periodic record with too few periods before any work.
/// Method: Pintelon (2002) Theorem 2: the sample-subspace estimates of B and D
/// need M >= 4 periods, those of A and C M >= 2.
/// Fails: Error(Input) at `meta_path` field "periods" naming M, or at
/// --skip-periods/--use-periods when the selection left too few.
void require_sample_subspace_periods(const RecordMeta& meta, const std::string& meta_path,
                                     const RecordSelection& selection = {});

/// How periodic records are turned into frequency-domain data (Section 5).
enum class RecordTreatment {
  Plain,               ///< Û, Ŷ and σ̂²_Y / M (sample-subspace algorithm, Section 4.1)
  ErrorsInVariables,   ///< noisy input: Ĝ = Ŷ/Û with the variance of Eq. (31)
  Improper             ///< improper G: identify 1/G by swapping input and output
};

/// Where the variance of the errors-in-variables data is evaluated.
enum class EivVariance {
  Data,   ///< Eq. (31) from the noisy ratio Ĝ (one pass)
  Model   ///< Eq. (31) at a first-pass model (second pass: consistent weight)
};
/// "data", "model" (identify-frf --eiv-variance, the certified cases' "eiv_variance").
const NameTable<EivVariance>& eiv_variance_names();

/// Where identify-frf's data came from and how they were treated: the
/// "source" object of its JSON (fdsid/json.hpp).
struct FrfSource {
  std::string frf_path;              ///< FRF CSV, or empty
  bool known_variance = false;       ///< the FRF CSV had a G_var column
  FrequencyUnits units;              ///< how its omega column was read (written when not the default)
  std::string data_path, meta_path;  ///< periodic records + meta, or empty
  int periods = 0;                   ///< M of the records; of an FRF file's sample variances (--frf-periods), else 0
  RecordTreatment treatment = RecordTreatment::Plain;
  EivVariance eiv_variance = EivVariance::Data;
  double min_input_snr = 10;         ///< the line rule of Eq. (34) (ErrorsInVariables, Improper)
  int dropped_lines = 0;             ///< lines dropped by that rule
  RecordSelection selection;         ///< columns by name, skipped periods (written when used)
  std::vector<double> noise_std;     ///< records: the known output noise std (--noise-std); empty: sample variance
};

/// V_SUB (Eq. 35) judged against its law under a right model and noise model
/// (review finding 16: it was printed with "about F when model and noise model
/// are right" and no verdict).
/// Method: V_SUB sums T = F p c weighted residuals |e|²/σ². At the true model
/// each is Exp(1) with a known variance (mean 1, variance 1) and F(2, 2M−2)
/// with the sample variance of M periods (mean d/(d−2), variance
/// d³/((d−2)²(d−4)), d = 2M − 2; M ≥ 4 gives a finite variance; for
/// errors-in-variables data to first order). Fitting the model only lowers
/// V_SUB, so the true-model law is conservative. Decision, distribution-free
/// (F(2, 6) terms are heavy-tailed): Cantelli's inequality
/// P(V ≥ mean + z std) ≤ 1/(1 + z²); a misfit when that bound is ≤ 1e-3
/// (z ≥ 31.6).
/// Fails: never; `available` is false without a noise model (an FRF file
/// without G_var: unit weights, V_SUB is no fit statistic).
struct FitVerdict {
  bool available = false;
  double v_sub = 0;
  int terms = 0;               ///< T = F p c
  int periods = 0;             ///< M of the sample variances (0: known variance)
  double expected = 0, std = 0;
  double ratio = 0;            ///< V_SUB / expected
  double z = 0;                ///< (V_SUB − expected) / std
  double p_bound = 1;          ///< P(X ≥ observed), X Fisher's combination of V_SUB's terms, at the true model
  bool misfit = false;
  /// The model is the --refine ml optimum; otherwise the warning names the
  /// refinement too: the Eq. (36) plant's subspace estimate from the lines
  /// below P/4 (its resonance above them) has V_SUB 12–56 × its expected value
  /// at r = 8–24, the ML refinement from it 1.00 ×.
  bool refined = false;
  /// The variances are an FRF file's G_var read as known (no --frf-periods):
  /// if they are sample variances over M periods (fdsid frf writes them so),
  /// the terms are F(2, 2M−2), heavier-tailed than Exp(1), and the test errs
  /// towards flagging; the warning then says how to tell it M.
  bool file_variance_as_known = false;
  std::string summary() const;  ///< the V_SUB line identify-frf prints
  std::string warning() const;  ///< empty unless misfit
};
FitVerdict fit_verdict(const FrfResult& result, const FrfData& data, const FrfSource& source);

/// An identification together with the data it was made from (what the
/// figure of identify-frf draws).
struct FrfRun {
  FrfData data;
  FrfResult result;
  int dropped_lines = 0;
};

/// Purpose: identify from the sample statistics of periodic records as
/// `fdsid identify-frf --data --meta [--eiv [--eiv-variance model] | --improper]`.
/// Method: Plain: identify_frf on stats.data. ErrorsInVariables:
/// errors_in_variables (corrected Eq. 31, lines below `min_input_snr` dropped),
/// identify_frf; with EivVariance::Model a second pass re-evaluates the
/// variance at the first-pass model and identifies again with the first
/// pass's order and r. Improper: swap_input_output, identify_frf (the model is
/// 1/G). A discrete-time model carries the records' sample time.
/// Fails: as errors_in_variables / swap_input_output and identify_frf.
/// References: Pintelon (2002) Sections 4.1 and 5, Eqs. (31), (34).
FrfRun identify_frf_records(const SampleStatistics& stats, const FrfOptions& options, RecordTreatment treatment,
                            EivVariance eiv_variance = EivVariance::Data, double min_input_snr = 10.0);

/// Order and r of an identification.
struct OrderAndR {
  int order = 0, r = 0;
};

/// Purpose: the order and r to hand to an identification that needs both
/// given (the 50-digit reference): options.order / options.r where set, else
/// the automatic choices.
/// Method: identify_frf in double precision with `options` (order from the
/// singular values of step 1c, r minimising V_SUB of Eq. 35) and its order, r.
/// Fails: as identify_frf.
/// References: Pintelon (2002) Section 5.
OrderAndR select_order_and_r(const FrfData& data, const FrfOptions& options);

/// The "method" name of an FRF identification: "pintelon2002-alg1" (discrete
/// time, Algorithm 1) or "pintelon2002-alg2-bilinear" / "-orthogonal"
/// (continuous time, Algorithm 2.1 / 2.2), "pintelon2002-alg1-bilinear" /
/// "-orthogonal" (discrete time, DiscreteMethod::Bilinear / Orthogonal).
std::string frf_method_name(Domain domain, ContinuousMethod method, DiscreteMethod discrete = DiscreteMethod::Monomial);

/// --method of identify-frf and check: the basis of the data's domain —
/// continuous time "bilinear" (Algorithm 2.1, the default) or "orthogonal"
/// (2.2); discrete time "monomial" (Algorithm 1, the default), "bilinear" or
/// "orthogonal" (DiscreteMethod). Empty: the domain's default. Sets
/// options.continuous / options.discrete; throws Error(Input) on "--method"
/// for a name of the other domain or an unknown one.
void set_frf_method(const std::string& name, Domain domain, FrfOptions& options);

// ---------------------------------------------------------------------------
// Power spectra of models

/// Purpose: refuse a model whose power spectrum is not defined before
/// sampling it (`fdsid sample-spectrum`).
/// Method: every pole of A strictly inside the unit circle (spectral radius
/// < 1) and as many inputs as outputs.
/// Fails: Error(Input) at `where` naming the pole modulus, or the shape.
void require_spectrum_model(const StateSpace& model, const std::string& where);

// ---------------------------------------------------------------------------
// Monte Carlo reproductions

/// Purpose: the Monte Carlo standard error of one ratio of standard deviations
/// of Pintelon (2002) Figs. 1b/2b.
/// Method: each sample standard deviation over N_r runs has relative standard
/// deviation ≈ 1/√(2 N_r) (Gaussian estimates); their ratio at most √2 times
/// that: √2 / √(2 N_r).
/// Fails: never (runs <= 0 gives +inf).
double std_ratio_standard_error(int runs);

// ---------------------------------------------------------------------------
// Oracle check (`fdsid check`)

/// The result of comparing a candidate model with the reference's.
struct OracleCheck {
  std::string candidate_path, data_path;
  int p = 0, r = 0;
  Method method = Method::Akcay2011;
  Extension extension = Extension::HermitianPart;
  ModelComparison comparison;
  double spectrum_tolerance = 0, pole_tolerance = 0, markov_tolerance = 0;  ///< markov: the summands' R(k)
  double factor_tolerance = 0, zero_tolerance = 0;  ///< the spectral factor's Markov parameters and zeros
  bool tolerance_given = false;  ///< by the user, instead of the derived rule
  nlohmann::json reference_model;
  /// Why the reference model has another order than the candidate (the
  /// reference failed at the candidate's order), or empty.
  std::string note;
  bool orders_agree() const { return comparison.candidate_order == comparison.reference_order; }
  bool poles_agree() const { return comparison.pole_distance <= pole_tolerance; }
  bool spectrum_agrees() const {
    return comparison.spectrum_error <= spectrum_tolerance && comparison.markov_error <= markov_tolerance;
  }
  /// The factor: zeros and H(k) within tolerance (a reflected zero fails both).
  bool factor_agrees() const {
    return comparison.zero_distance <= zero_tolerance && comparison.factor_markov_error <= factor_tolerance;
  }
  /// Same order, and poles, spectrum, summands and factor within tolerance.
  bool agree() const { return orders_agree() && poles_agree() && spectrum_agrees() && factor_agrees(); }
  /// One line naming what failed (or "AGREES: ..."), as `fdsid check` prints it;
  /// for a factor that is not minimum phase: "factor: zero 1.049 outside the
  /// unit circle; the minimum-phase factor has it at 0.953".
  std::string summary() const;
};

/// The result of comparing a candidate model of FRF samples or periodic
/// records with the reference's identification of the same data at the same
/// settings (`fdsid check --frf` / `--data --meta`).
struct FrfOracleCheck {
  std::string candidate_path, data_path, meta_path;  ///< data_path: the FRF or the records
  int order = 0, r = 0;
  Domain domain = Domain::Discrete;
  ContinuousMethod method = ContinuousMethod::Bilinear;
  double omega_scale = 0;                ///< ω_s used (continuous)
  std::string method_name;               ///< frf_method_name
  std::string settings_note;             ///< where r, method, ω_s came from
  /// A candidate of another order than the data support: "the data support
  /// order k (…); the candidate has order n", or the reference's failure at
  /// the candidate's order and the order it was compared at instead.
  std::string order_note;
  FrfModelComparison comparison;
  double backward_perturbation = 0;      ///< relative size of the perturbations behind the tolerance
  FrfTolerance tolerance;
  nlohmann::json reference_model;
  bool agree() const { return comparison.agree(); }
  /// "AGREES: G on the data grid ... (tol ..., ratio ...), on a dense grid ..., poles ..."
  /// or "DISAGREES: ..." with what failed first.
  std::string summary() const;
};

/// Purpose: the tolerances of `fdsid check` (spectra) and the verdict.
/// Method: tolerance > 0 is used for every quantity. Else each compared
/// quantity q (poles, spectrum, summands' Markov parameters, factor zeros,
/// factor Markov parameters; compare_models) gets
///   tol_q = 10 (max_i q(perturbed_i, reference) + max_j q(rounded_j, reference)):
/// `perturbed` are the reference's identifications of the same spectrum with
/// the backward errors of a correct double-precision implementation put into
/// Algorithm 1 in random directions (reference::BackwardPerturbation, sizes
/// from oracle_backward_errors); rounded_j are the reference's model with A,
/// B, C, D each moved by 4n u times its norm in three random directions (the
/// rounding of the candidate's own numbers and of evaluating them). How far
/// these move q is what rounding does on these data to first order
/// (statistical condition estimation, Kenney & Laub 1994); the factor 10 over
/// three samples as in FrfTolerance (compare.hpp).
/// Fails: Error(Input) without perturbed models and without a tolerance.
void set_oracle_tolerances(OracleCheck& check, const StateSpace& reference, const std::vector<StateSpace>& perturbed,
                           double tolerance);

/// The relative backward errors set_oracle_tolerances assumes of a correct
/// double implementation of Algorithm 1 at p, r, m, N = 2M, order n:
/// 𝒴 by (log2 N + √(pm · rm)) u (the FFT's error in the Fourier coefficients,
/// Higham 2002 Thm 24.2 in its log2 N u form, plus the probabilistic backward
/// error of the SVD, Higham & Mary 2019), step 8's design matrix, column by
/// column, and right-hand side by √(rows · cols) u with rows = 2(M+1)m² and
/// cols = m(m+1)/2 + nm (Householder QR), Ê and F̂ of step 9 by 4n u per
/// step of a doubling solver (SDA, fast/'s method; a Schur-vector solver does
/// no worse), which needs K = 1 + ⌈log2(ln u / ln ρ_z²)⌉ steps for the closed
/// loop's powers A_z^(2^K) to fall below u (ρ_z: the reference factor's largest
/// zero modulus, the spectral radius of A_z = A − B D⁻¹ C).
struct OracleBackwardErrors {
  double data_matrix = 0, least_squares = 0, riccati = 0;
};
OracleBackwardErrors oracle_backward_errors(int p, int r, int m, int M, int n, double rho_z);

/// The relative backward error FrfTolerance (compare.hpp) assumes of a correct
/// double implementation of Pintelon (2002) on `data` at r: √(rows · cols) u
/// with rows × cols = 2Fc × r(m+p), the shape of Zᵀ (the probabilistic
/// size of Householder QR's column-wise backward error, Higham & Mary 2019).
double frf_backward_error(const FrfData& data, int r);

}  // namespace fdsid
