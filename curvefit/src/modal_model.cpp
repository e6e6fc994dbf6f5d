// The fitted modal model evaluated for an FRF named by its measured DOFs (the HTML report draws
// the fit over the measured FRFs with it).
#include <cmath>

#include "ema/curvefit/fit.hpp"

namespace ema::curvefit {

Eigen::VectorXcd SynthesiseMeasuredFrf(const ModalModel& model, const Dof& response, const Dof& reference,
                                       const Eigen::VectorXd& frequency_hz) {
  Eigen::VectorXcd out = Eigen::VectorXcd::Constant(frequency_hz.size(), {kNaN, kNaN});
  const int outputs = static_cast<int>(model.outputs.size()), references = static_cast<int>(model.references.size());
  for (int o = 0; o < outputs; ++o)
    for (int i = 0; i < references; ++i) {
      // Fitting orientation: output o, reference i; measured: swapped when fitted by reciprocity.
      const Dof& measured_response = model.transposed ? model.references[i] : model.outputs[o];
      const Dof& measured_reference = model.transposed ? model.outputs[o] : model.references[i];
      if (!(measured_response == response && measured_reference == reference)) continue;
      const Eigen::VectorXcd h = SynthesiseFrf(model, o, i, frequency_hz);
      for (Eigen::Index k = 0; k < frequency_hz.size(); ++k) {
        const double f = frequency_hz[k];
        if (f > 0.0 && f >= model.band_lo_hz && f <= model.band_hi_hz) out[k] = h[k];
      }
      return out;
    }
  return out;
}

}  // namespace ema::curvefit
