// Links against the installed libraries and uses a type from the public headers.
#include <iostream>

#include "ema/core/types.hpp"

int main() {
  const std::complex<double> pole = ema::FrequencyAndDampingToPole(100.0, 0.01);
  double f = 0.0, zeta = 0.0;
  ema::PoleToFrequencyAndDamping(pole, &f, &zeta);
  std::cout << "consumer: " << f << " Hz, zeta " << zeta << "\n";
  return (std::abs(f - 100.0) < 1e-9 && std::abs(zeta - 0.01) < 1e-12) ? 0 : 1;
}
