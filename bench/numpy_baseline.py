#!/usr/bin/env python3
"""Peer baseline: small dense numpy implementations of the two algorithms that
bench_frf (BM_IdentifyFrf) and bench_spectrum (BM_Identify) time, written from
the papers (not ported from fast/):

  * Pintelon, Automatica 38 (2002) 1295-1311, Algorithm 1 (discrete time, FRF
    data, SISO, known noise variance), steps 1a-3.
  * Akcay, Automatica 47 (2011) 363-367, Algorithm 1 (power spectrum, m = 1),
    steps 1-9.

The workloads are those of bench/bench_frf.cpp and bench/bench_spectrum.cpp:
same plants, grids, noise levels and orders; the noise realisations differ
(numpy's generator, not std::mt19937_64), which does not change the work.
Only the algorithm steps are timed here; the C++ functions additionally compute
diagnostics (condition estimates, V_SUB, minimum of the fitted spectrum, ...).

Usage:
  python3 bench/numpy_baseline.py            # timings, one JSON line per workload
  python3 bench/numpy_baseline.py --check    # noise-free pole recovery checks
  python3 bench/numpy_baseline.py --reps 7 --only frf/999/8

Timing: the median (and the minimum) of --reps (>= 5) repetitions of one
identification, time.perf_counter, data generated outside the timed region.
BLAS/LAPACK threads are pinned to 1 before numpy is imported.
Not part of CI; bench/peer-ratios.sh runs it next to the Google Benchmark
binaries.
"""
import os

for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS",
           "BLIS_NUM_THREADS", "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

# ---------------------------------------------------------------------------
# The example systems (printed decimal values of the papers).


def mckelvey_system(a34):
    """Fourth-order system of McKelvey et al. (1996): Pintelon (2002) Eq. (36)
    with A(3,4) = 0.064516, Akcay (2011) Section 4 with A(3,4) = 0.0645.
    B(4) = 0.1290 and C(4) = 1.6129 as printed in Akcay (2011)."""
    A = np.array([[0.8876, 0.4494, 0.0, 0.0],
                  [-0.4494, 0.7978, 0.0, 0.0],
                  [0.0, 0.0, -0.6129, a34],
                  [0.0, 0.0, -6.4516, -0.7419]])
    B = np.array([[0.2247], [0.8989], [0.0323], [0.1290]])
    C = np.array([[0.4719, 0.1124, 9.6774, 1.6129]])
    D = np.array([[0.9626]])
    return A, B, C, D


def transfer(A, B, C, D, z):
    """SISO G(z) = D + C (zI - A)^{-1} B at the points z (1-D array)."""
    n = A.shape[0]
    X = np.linalg.solve(z[:, None, None] * np.eye(n) - A, np.broadcast_to(B, (len(z), n, 1)))
    return D[0, 0] + (C @ X)[:, 0, 0]


def resolvent_rows(A, C, z):
    """Rows C (z_k I - A)^{-1} (len(z) x n) for a 1 x n C, through the
    eigen-decomposition A = V diag(lam) V^{-1}: (C V) diag(1/(z_k - lam)) V^{-1},
    vectorised over k (A is assumed diagonalisable: distinct poles, as both
    papers assume). A batched np.linalg.solve of the len(z) shifted n x n systems
    gives the same rows but costs about 1 us of gufunc overhead per point
    (~95 ms at F = 10^5), which would dominate the baseline."""
    lam, V = np.linalg.eig(A)
    return ((C @ V) / (z[:, None] - lam[None, :])) @ np.linalg.inv(V)


# ---------------------------------------------------------------------------
# Pintelon (2002) Algorithm 1, discrete time, SISO, known variance.


def pintelon_alg1(omega, U, Y, var, n, r):
    """omega (F), U, Y (F complex), var = sigma_Y^2(k) (F). Returns A, B, C, D."""
    F = omega.size
    # (1a) W_r(k) = [1, z_k, ..., z_k^{r-1}]^T (Eq. 7, xi = z), columns of an r x F matrix.
    W = np.exp(1j * np.outer(np.arange(r), omega))
    Ub = W * U  # bold U of Eq. (9), r x F
    Yb = W * Y  # bold Y of Eq. (9)
    # Eq. (11), (18): Z = [U^re; Y^re], ^re puts Re and Im side by side (2r x 2F).
    Z = np.block([[Ub.real, Ub.imag], [Yb.real, Yb.imag]])
    # Eq. (18): C_Y = Re(C C^H), C = [W_r(1) sigma_Y(1) ... W_r(F) sigma_Y(F)].
    CY = ((W * var) @ W.conj().T).real
    # (1b) Z^T = Q R; R22 is the lower-right r x r block of R.
    R = np.linalg.qr(Z.T, mode="r")
    R22T = R[r:, r:].T
    # (1c) SVD of C_Y^{-1/2} R22^T with C_Y^{1/2} = L, the Cholesky factor
    # (C_Y = L L^T); O_r = C_Y^{1/2} U[:, :n].
    L = np.linalg.cholesky(CY)
    Us, _, _ = np.linalg.svd(np.linalg.solve(L, R22T))
    O = L @ Us[:, :n]
    # (2) Eq. (19): shift property (12) in least squares, C = first row.
    A = np.linalg.lstsq(O[:-1], O[1:], rcond=None)[0]
    C = O[:1, :]
    # (3) Eq. (17) with W(k) = 1/sigma_Y(k): linear least squares in (B, D),
    # real and imaginary parts stacked.
    chi = resolvent_rows(A, C, np.exp(1j * omega))  # C (z_k I - A)^{-1}, F x n
    w = 1.0 / np.sqrt(var)
    K = np.column_stack([chi * U[:, None], U]) * w[:, None]
    rhs = Y * w
    theta = np.linalg.lstsq(np.vstack([K.real, K.imag]), np.concatenate([rhs.real, rhs.imag]), rcond=None)[0]
    return A, theta[:n].reshape(n, 1), C, theta[n:].reshape(1, 1)


def frf_data(F, sigma2=1e-4, seed=2002):
    """bench_frf.cpp make_data: Eq. (36) plant, omega_k = pi k / (F+1), k = 1..F,
    |U| = 1 with random phases, output noise CN(0, sigma2), that variance declared."""
    A, B, C, D = mckelvey_system(0.064516)
    rng = np.random.default_rng(seed)
    omega = np.pi * np.arange(1, F + 1) / (F + 1)
    U = np.exp(1j * rng.uniform(-np.pi, np.pi, F))
    Y = transfer(A, B, C, D, np.exp(1j * omega)) * U
    if sigma2 > 0:
        Y = Y + np.sqrt(sigma2 / 2) * (rng.standard_normal(F) + 1j * rng.standard_normal(F))
    var = np.full(F, sigma2 if sigma2 > 0 else 1e-4)
    return omega, U, Y, var


# ---------------------------------------------------------------------------
# Akcay (2011) Algorithm 1, m = 1.


def sda_riccati(A, C, E, F, tol=1e-14, maxit=100):
    """Step 9: P = A P A^T + (F - A P C^T)(E - C P C^T)^{-1}(F - A P C^T)^T,
    the minimal (stabilising) solution.

    Method: the structure-preserving doubling algorithm (Chu, Fan, Lin 2005) on
    the equivalent DARE for X = -P,
        X = A X A^T - (A X C^T + F)(E + C X C^T)^{-1}(A X C^T + F)^T,
    with the cross term removed (Abar = A - F E^{-1} C, H = -F E^{-1} F^T,
    G = C^T E^{-1} C) and written in control form with a = Abar^T:
        A_{k+1} = A_k W^{-1} A_k, G_{k+1} = G_k + A_k W^{-1} G_k A_k^T,
        H_{k+1} = H_k + A_k^T H_k W^{-1} A_k,  W = I + G_k H_k.
    H_k is the Riccati difference (Kalman filter) iterate number 2^k started
    from P = 0, so it converges to the minimal solution; -H_k -> P.
    Falls back to that plain fixed-point iteration if doubling breaks down.
    Returns P, the relative residual and the method used."""
    n = A.shape[0]
    Ei = np.linalg.inv(E)
    Abar = A - F @ Ei @ C
    Ak, Gk, Hk = Abar.T.copy(), C.T @ Ei @ C, -F @ Ei @ F.T
    I = np.eye(n)
    for _ in range(maxit):
        Wi = np.linalg.inv(I + Gk @ Hk)
        AW = Ak @ Wi
        Hn = Hk + Ak.T @ Hk @ Wi @ Ak
        Gk = Gk + AW @ Gk @ Ak.T
        Ak = AW @ Ak
        done = np.linalg.norm(Hn - Hk) <= tol * max(1.0, np.linalg.norm(Hn))
        Hk = Hn
        if done or not np.all(np.isfinite(Hk)):
            break
    P = -(Hk + Hk.T) / 2

    def ric(P):
        K = F - A @ P @ C.T
        return A @ P @ A.T + K @ np.linalg.solve(E - C @ P @ C.T, K.T)

    res = np.linalg.norm(P - ric(P)) / max(np.linalg.norm(P), 1e-300)
    method = "sda"
    if not np.isfinite(res) or res > 1e-8:  # fall-back: Riccati difference iteration from 0
        P = np.zeros((n, n))
        for _ in range(100000):
            Pn = ric(P)
            if np.linalg.norm(Pn - P) <= 1e-15 * np.linalg.norm(Pn):
                P = Pn
                break
            P = Pn
        res = np.linalg.norm(P - ric(P)) / np.linalg.norm(P)
        method = "fixed-point"
    return P, res, method


def akcay_alg1(S, n, p, r):
    """S: M+1 complex samples S(e^{i pi k/M}), k = 0..M. Returns A, B, C, D of the
    minimum-phase spectral factor and the Riccati residual."""
    M = S.size - 1
    N = 2 * M
    # (1) S_{M+k} = S_{M-k+2}: the even extension to N = 2M points; with the
    # Hermitian-part reading (fdsid's default, Extension::HermitianPart) the
    # samples are replaced by Re S_k first, so the extended sequence is real and even.
    # (2) Eq. (20): s_k = (1/N) sum_j e^{i 2 pi jk/N} S_j -- the inverse real FFT of
    # the M+1 half-spectrum samples is exactly that inverse DFT of the extension.
    s = np.fft.irfft(S.real, n=N)
    # (3) Eq. (19): Y_kl = s_{k+l-1} + s_{N-p-r+k+l-1}, 1 <= k <= p, 1 <= l <= r; dense SVD.
    h = np.arange(p)[:, None] + np.arange(r)[None, :] + 1
    Yh = s[h] + s[N - p - r + h]
    Uy, _, _ = np.linalg.svd(Yh)
    U2n = Uy[:, :2 * n]
    # (5) A~ = (J_d U_2n)^+ J_u U_2n
    At = np.linalg.lstsq(U2n[:-1], U2n[1:], rcond=None)[0]
    # (6) eigen-decomposition of A~, keep the n eigenvalues inside the unit circle.
    # The Jordan form is taken in its real block version (a +- ib -> [[a, b], [-b, a]],
    # basis [Re v, Im v]) so that A^, C^, E^, F^, B^, D^ are real.
    lam, V = np.linalg.eig(At)
    inside = np.abs(lam) < 1
    if inside.sum() != n:
        raise RuntimeError("step 6: %d eigenvalues inside the unit circle, expected %d" % (inside.sum(), n))
    cols, Ah = [], np.zeros((n, n))
    for li, vi in zip(lam[inside], V[:, inside].T):
        i = len(cols)
        if abs(li.imag) <= 1e-12 * abs(li):
            cols.append(vi.real / np.linalg.norm(vi.real))
            Ah[i, i] = li.real
        elif li.imag > 0:
            cols += [vi.real, vi.imag]
            Ah[i:i + 2, i:i + 2] = [[li.real, li.imag], [-li.imag, li.real]]
    Pi_c = np.column_stack(cols)
    # (7) C^ = J_f U_2n Pi_c
    Ch = U2n[:1] @ Pi_c
    # (8) min sum_k |chi(z_k) F + F^T chi^T(1/z_k) + E - S_k|^2 over the M+1 samples,
    # chi(z) = C^ (zI - A^)^{-1}. For m = 1 and real A^, C^, F on |z| = 1 the model is
    # 2 Re(chi(z_k)) F + E (real), so the imaginary part of S_k only adds a constant:
    # real least squares of Re S_k on [2 Re chi(z_k), 1].
    z = np.exp(1j * np.pi * np.arange(M + 1) / M)
    chi = resolvent_rows(Ah, Ch, z)
    theta = np.linalg.lstsq(np.column_stack([2 * chi.real, np.ones(M + 1)]), S.real, rcond=None)[0]
    Fh = theta[:n].reshape(n, 1)
    Eh = theta[n:].reshape(1, 1)
    # (9) Riccati, then B^ = (F - A P C^T)(E - C P C^T)^{-1/2}, D^ = (E - C P C^T)^{1/2}.
    P, res, method = sda_riccati(Ah, Ch, Eh, Fh)
    Re = Eh - Ch @ P @ Ch.T
    if Re[0, 0] <= 0:
        raise RuntimeError("step 9: E - C P C^T not positive")
    Dh = np.sqrt(Re)
    Bh = (Fh - Ah @ P @ Ch.T) / Dh[0, 0]
    return Ah, Bh, Ch, Dh, "%s residual %.1e" % (method, res)


def spectrum_data(M, eps=1e-3, seed=12345):
    """bench_spectrum.cpp noisy_data: S(z) = G(z) G(1/z) of the Akcay (2011)
    Section 4 system at z_k = e^{i pi k/M}, k = 0..M, plus eps H(z_k) v_k with
    v_k ~ CN(0, 1) (Re, Im each N(0, 1/2)) and H the Section 4 noise filter."""
    A, B, C, D = mckelvey_system(0.0645)
    z = np.exp(1j * np.pi * np.arange(M + 1) / M)
    S = transfer(A, B, C, D, z) * transfer(A, B, C, D, 1 / z)
    if eps > 0:
        rng = np.random.default_rng(seed)
        v = np.sqrt(0.5) * (rng.standard_normal(M + 1) + 1j * rng.standard_normal(M + 1))
        H = (0.2 * z * z - 0.0904 * z + 0.1839) / (z * z - 1.1111 * z + 0.8520)
        S = S + eps * H * v
    return S


# ---------------------------------------------------------------------------


def pole_error(A_est, A_true):
    """Largest distance from a true pole to its nearest estimated pole, relative."""
    pe, pt = np.linalg.eigvals(A_est), np.linalg.eigvals(A_true)
    return max(np.min(np.abs(pe - t)) for t in pt) / max(np.abs(pt))


def check():
    ok = True
    tol = 1e-8
    print("# noise-free checks (pole error = max over true poles of min |p^ - p| / max|p|)")
    A0, B0, C0, D0 = mckelvey_system(0.064516)
    for F, r in [(999, 8), (999, 40), (100000, 8)]:
        omega, U, Y, var = frf_data(F, sigma2=0.0)
        A, B, C, D = pintelon_alg1(omega, U, Y, var, 4, r)
        z = np.exp(1j * omega)
        perr = pole_error(A, A0)
        gerr = np.max(np.abs(transfer(A, B, C, D, z) - transfer(A0, B0, C0, D0, z)))
        good = perr < tol and gerr < 1e-7
        ok &= good
        print("pintelon2002 F=%d r=%d: pole error %.2e, max |G^ - G| %.2e  %s"
              % (F, r, perr, gerr, "ok" if good else "FAIL"))
    A0, B0, C0, D0 = mckelvey_system(0.0645)
    zeros0 = np.linalg.eigvals(A0 - B0 @ C0 / D0[0, 0])
    for M in [1000, 32000]:
        S = spectrum_data(M, eps=0.0)
        A, B, C, D, res = akcay_alg1(S, 4, 50, 50)
        z = np.exp(1j * np.pi * np.arange(M + 1) / M)
        Sh = transfer(A, B, C, D, z) * transfer(A, B, C, D, 1 / z)
        perr = pole_error(A, A0)
        serr = np.max(np.abs(Sh - S)) / np.max(np.abs(S))
        zh = np.linalg.eigvals(A - B @ C / D[0, 0])
        good = perr < tol and serr < 1e-8
        ok &= good
        print("akcay2011 M=%d p=r=50: pole error %.2e, max|S^ - S|/max|S| %.2e, Riccati %s, "
              "|zeros| max %.4f (true %.4f)  %s"
              % (M, perr, serr, res, np.max(np.abs(zh)), np.max(np.abs(zeros0)), "ok" if good else "FAIL"))
    print("# all checks " + ("passed" if ok else "FAILED"))
    return ok


def workloads():
    """(name, setup) pairs; setup() returns the zero-argument function to time."""
    out = []
    for F in (999, 100000):
        for r in (8, 40):
            def setup(F=F, r=r):
                d = frf_data(F)
                return lambda: pintelon_alg1(*d, 4, r)
            out.append(("frf/%d/%d" % (F, r), setup))
    for M in (1000, 32000, 1000000):
        def setup(M=M):
            S = spectrum_data(M)
            return lambda: akcay_alg1(S, 4, 50, 50)
        out.append(("spectrum/%d" % M, setup))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true", help="noise-free pole recovery checks")
    ap.add_argument("--reps", type=int, default=7, help="timed repetitions per workload (>= 5)")
    ap.add_argument("--only", action="append", help="workload name (repeatable); default all")
    a = ap.parse_args()
    if a.check:
        return 0 if check() else 1
    reps = max(5, a.reps)
    for name, setup in workloads():
        if a.only and name not in a.only:
            continue
        f = setup()
        f()  # warm-up, not timed
        t = []
        for _ in range(reps):
            t0 = time.perf_counter()
            f()
            t.append(time.perf_counter() - t0)
        print(json.dumps({"workload": name, "seconds": float(np.median(t)), "min_seconds": min(t),
                          "reps": reps, "numpy": np.__version__}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
