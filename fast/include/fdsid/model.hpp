#pragma once
/// State-space models, their transfer functions, power spectra and spectral
/// summands (Akçay 2011, Section 2 and the opening of Section 3).
#include <complex>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "fdsid/names.hpp"

namespace fdsid {

using cplx = std::complex<double>;

enum class Domain { Discrete, Continuous };

/// "discrete", "continuous": the model format's "domain", the CLI's --domain.
const NameTable<Domain>& domain_names();
const char* to_string(Domain d);

/// x[t+1] = A x[t] + B u[t], y[t] = C x[t] + D u[t] (discrete), or
/// dx/dt = A x + B u, y = C x + D u (continuous). Akçay (2011) Eq. (1).
struct StateSpace {
  Domain domain = Domain::Discrete;
  double sample_time = 1.0;
  Eigen::MatrixXd A, B, C, D;

  int order() const { return static_cast<int>(A.rows()); }
  int inputs() const { return static_cast<int>(B.cols()); }
  int outputs() const { return static_cast<int>(C.rows()); }
};

/// Checks the shapes of A, B, C, D and that every entry is finite; throws
/// Error(Input) naming the matrix otherwise.
void validate(const StateSpace& model, const std::string& where = "model");

/// G(z) = D + C (zI - A)^{-1} B, Akçay (2011) Eq. (2). Solved by LU of zI - A.
Eigen::MatrixXcd transfer(const StateSpace& model, cplx z);

/// S(z) = G(z) G^T(1/z), Akçay (2011) Eq. (3). On |z| = 1 this is G(z) G(z)^H.
Eigen::MatrixXcd power_spectrum(const StateSpace& model, cplx z);

/// Eigenvalues of A (the poles), sorted by modulus then argument.
Eigen::VectorXcd poles(const StateSpace& model);

/// A pole as text, "re+imj" / "re-imj" with 6 significant digits each (warnings, notes).
std::string pole_text(cplx z);

/// Whether a pole is unstable: discrete |z| >= 1, continuous Re s >= 0.
bool unstable_pole(Domain domain, cplx pole);

/// The unstable poles as text, or "" when there is none: the worst one first,
/// "pole Z of modulus M >= 1" (discrete) or "pole S with real part >= 0"
/// (continuous), and when there are more, all of them, worst first, in
/// parentheses (a user review: the Silverbox at --allow-unstable has six and
/// the warning named one).
std::string unstable_poles_text(Domain domain, const Eigen::VectorXcd& poles);

/// Throws Error(Input) naming the unstable poles (unstable_poles_text) when
/// the model is not stable: an unstable model has no periodic steady state,
/// and `use` says what needed one ("to compare", "to record", ...).
void require_stable(const StateSpace& model, const std::string& use);

/// The largest pole modulus, max |λ_i(A)| (0 for order 0); a discrete-time
/// model is stable when it is < 1.
double spectral_radius(const StateSpace& model);

/// A lightly damped pole pair whose resonance lies outside a frequency band
/// (review finding 29: a resonance above the excited lines was identified far
/// off without a word). Each pair is represented by its pole of positive
/// imaginary part; discrete poles are read as s = log z (rad/sample).
/// Criterion: a resonance peak exists (ζ < 1/√2, i.e. |Re s| < |Im s|) and
/// its half-power band [ω_d − |Re s|, ω_d + |Re s|] (ω_d = Im s) misses
/// [lo, hi] entirely: only the tail of the mode reaches the band, which fixes
/// its contribution there but not its frequency and damping separately.
struct OutOfBandResonance {
  cplx pole;           ///< the model's pole (z for discrete, s for continuous)
  double frequency;    ///< ω_d = Im s: rad/sample (discrete) or rad/s (continuous)
  double damping;      ///< ζ = −Re s / |s|
  bool above;          ///< above hi (else below lo)
};
std::vector<OutOfBandResonance> resonances_outside_band(const Eigen::VectorXcd& poles, Domain domain, double lo,
                                                        double hi);
/// The warning for one such pair, "" for none: the pole, its resonance and
/// damping, the band, what it means and what to do. `excited` names the band
/// ("the excited lines", "the FRF's frequencies"); frequencies are printed
/// in the band's unit (rad/sample, or rad/s for continuous time).
std::string out_of_band_warning(const std::vector<OutOfBandResonance>& found, Domain domain, double lo, double hi,
                                const std::string& excited);

/// Transmission zeros of a square model: the finite generalised eigenvalues of
/// the Rosenbrock pencil ([A B; C D], [I 0; 0 0]) by real QZ (Eigen's
/// GeneralizedEigenSolver); infinite ones are dropped (an infinite eigenvalue
/// comes back with β ≈ u‖pencil‖, so |α/β| ≥ 1e10 max(1, ‖pencil‖_F) is read
/// as infinite). Sorted like poles(). Empty for a non-square
/// model or order 0.
Eigen::VectorXcd zeros(const StateSpace& model);

/// Solution P of the discrete Lyapunov equation P = A P A^T + Q for stable A.
/// Method: Smith's doubling, P <- P + A_k P A_k^T, A_k <- A_k^2, until A_k
/// is negligible; O(n^3 log(log u / log rho(A))). Throws Error(Numerical)
/// when A is not stable.
Eigen::MatrixXd lyapunov(const Eigen::MatrixXd& A, const Eigen::MatrixXd& Q);

/// The spectral summands of Akçay (2011) Section 3:
/// S(z) = E + C (zI - A)^{-1} F + F^T (z^{-1} I - A^T)^{-1} C^T,
/// E = C P C^T + D D^T, F = A P C^T + B D^T, P = A P A^T + B B^T.
struct SpectralSummands {
  Eigen::MatrixXd A, C, E, F, P;
};

SpectralSummands spectral_summands(const StateSpace& model);

/// S(z) from the summands (on the unit circle: E + X + X^H, X = C (zI-A)^{-1} F).
Eigen::MatrixXcd summand_spectrum(const SpectralSummands& s, cplx z);

/// Akçay (2011) Eq. (3) sampled at omega_k = pi (k-1)/M, k = 1..M+1.
/// Returns (m*m) x (M+1): column k holds vec(S_k) (column-major m x m).
Eigen::MatrixXcd sample_spectrum(const StateSpace& model, int M);

/// Extended observability matrix O_r = [C; CA; ...; CA^{r-1}] (Pintelon 2002 Eq. 7).
Eigen::MatrixXd observability(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C, int r);

/// Pintelon (2002) Eq. (14): the estimate (Â, B̂, Ĉ) referred to the realisation
/// (A, C) of `reference`: Â_T = T^{-1} Â T, B̂_T = T^{-1} B̂, Ĉ_T = Ĉ T with
/// T = Ô_r^+ O_r (least squares by Householder QR). Invariant under any
/// similarity applied to the estimate; D is unchanged.
StateSpace refer_realization(const StateSpace& estimate, const StateSpace& reference, int r);

}  // namespace fdsid
