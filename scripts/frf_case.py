#!/usr/bin/env python3
"""An FRF test case for `fdsid check` (scripts/check-tightness.sh): a modal
system of order n (n/2 pole pairs), sampled at F frequencies, written as the
FRF CSV of README "File formats" with a G_var column.

usage: frf_case.py KIND N PAR F REL SEED OUT.csv
  KIND d: discrete, poles PAR * exp(j theta_i), theta spread over (0, 0.9 pi),
          omega = pi (k + 1/2) / F rad/sample;
  KIND c: continuous, modes w0 = 10^(-2 + 4 (i + 1/2) / (n/2)) rad/s with
          damping ratio PAR, omega log-spaced over 10^-2.5 .. 10^2.5 rad/s;
  REL > 0: complex Gaussian noise of relative std REL (G_var = REL^2 |G|^2);
  REL = 0: noise-free, G_var = 1e-6 |G|^2 (weights only).
Standard library only (no numpy)."""
import cmath, math, random, sys
if len(sys.argv) != 8:
    sys.exit(__doc__)
kind, n, par, F, rel, seed, out = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4]), float(sys.argv[5]), int(sys.argv[6]), sys.argv[7]
random.seed(seed)
# modal system: n/2 pole pairs
poles=[]; res=[]
for i in range(n//2):
    if kind=='d':
        th = math.pi*(i+0.5)/(n//2)*0.9 + random.uniform(-0.05,0.05)
        poles.append(par*cmath.exp(1j*th))
    else:
        w0 = 10**(-2+4*(i+0.5)/(n//2)); z=par
        poles.append(complex(-z*w0, w0*math.sqrt(1-z*z)))
    res.append(complex(random.gauss(0,1),random.gauss(0,1))*(abs(poles[-1]) if kind=='c' else 1))
D=random.gauss(0,1)
def G(x):
    return D+sum(r/(x-p)+r.conjugate()/(x-p.conjugate()) for p,r in zip(poles,res))
with open(out,'w') as f:
    f.write('omega,G_re,G_im,G_var\n')
    for k in range(F):
        if kind=='d': w=math.pi*(k+0.5)/F; x=cmath.exp(1j*w)
        else: w=10**(-2.5+5*k/(F-1)); x=1j*w
        g=G(x); v=max(rel*rel*abs(g)**2,1e-300) if rel>0 else 1e-6*abs(g)**2
        if rel>0:
            s=math.sqrt(v/2); g+=complex(random.gauss(0,s),random.gauss(0,s))
        f.write('%.17g,%.17g,%.17g,%.17g\n'%(w,g.real,g.imag,v))
