// Uses the installed fdsid: identifies Akçay's example (Eq. 36 of the 2011
// paper, fdsid/paper.hpp) from 65 noise-free spectrum samples with fdsid::fast,
// and evaluates the first sample of the reference's spectrum in 50 digits.
// Exit 0 when the identified order is the true 4 and the two libraries give the
// same S(1) to double precision (both are noise-free evaluations of one model:
// relative difference a few units of 1e-16, 1e-12 leaves 4 digits of room for
// the Lyapunov solve's conditioning); prints what it found.
#include <cmath>
#include <iostream>

#include "fdsid/paper.hpp"
#include "fdsid/reference/spectrum_id.hpp"
#include "fdsid/spectrum_id.hpp"

int main() {
  const fdsid::StateSpace sys = fdsid::akcay_example_system();
  fdsid::SpectrumData data;
  data.M = 64;
  data.S = fdsid::sample_spectrum(sys, data.M);
  const fdsid::SpectrumResult fit = fdsid::identify_spectrum(data, fdsid::SpectrumOptions{});

  fdsid::reference::Model ref;
  ref.A = sys.A.cast<fdsid::reference::Real>();
  ref.B = sys.B.cast<fdsid::reference::Real>();
  ref.C = sys.C.cast<fdsid::reference::Real>();
  ref.D = sys.D.cast<fdsid::reference::Real>();
  const fdsid::reference::Spectrum s = fdsid::reference::sample_spectrum(ref, 1);
  const double s0 = static_cast<double>(s.S.front()(0, 0).real());
  const double rel = std::abs(s0 - data.S(0, 0).real()) / std::abs(s0);
  std::cout << "order " << fit.model.A.rows() << ", S(1) relative difference " << rel << "\n";
  return fit.model.A.rows() == 4 && rel < 1e-12 ? 0 : 1;
}
