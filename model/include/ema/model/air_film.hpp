// Load-lift curve of a circular porous aerostatic pad from its geometry, permeability and supply
// pressure (thesis section 6.2.1, 1D radial flow), in the viscous isothermal limit:
//
//   Darcy flow through the porous layer (thickness t, permeability kappa) feeds a radial
//   Poiseuille flow in the film (gap h). With P = p^2 mass conservation gives
//   (1/r) d/dr (r dP/dr) = L^2 (P - Ps^2),  L^2 = 12 kappa / (t h^3),
//   P'(0) = 0, P(R) = Pa^2  =>  P(r) = Ps^2 - (Ps^2 - Pa^2) I0(L r) / I0(L R),
//   W(h) = integral over the pad of (p - Pa) dA.
//
// Gas inertia and the Mach-number terms of the thesis's generalised 1D flow (Plante et al.) are
// neglected, which is the usual approximation at gaps of a few micrometres.
#pragma once

#include "ema/model/model.hpp"

namespace ema::model {

struct PorousPad {
  double diameter = 0.0;             ///< m
  double thickness = 0.0;            ///< porous layer thickness, m
  double permeability = 0.0;         ///< m^2
  double supply_pressure = 0.0;      ///< gauge, Pa
  double ambient_pressure = 101325.0;  ///< absolute, Pa
  double gap_min = 1e-6;             ///< tabulated gap range, m
  double gap_max = 40e-6;
  int points = 80;                   ///< tabulated points (log-spaced in gap)
};

/// Load capacity W(h) in N (throws InputError on non-positive parameters).
double PorousPadLoad(const PorousPad& pad, double gap);

/// The pad's load-lift curve tabulated on [gap_min, gap_max] as an air_film law.
AirFilmLaw PorousPadCurve(const PorousPad& pad, double operating_gap);

}  // namespace ema::model
