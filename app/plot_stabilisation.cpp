// PLplot renders into a private temporary file; its bytes are then handed to
// WriteFileAtomically so that a failed run never leaves a half-written picture.
#include "plot_stabilisation.hpp"

#include <plplot.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <mutex>
#include <sstream>
#include <string>
#include <unistd.h>

#include "ema/core/error.hpp"
#include "ema/formats/atomic_file.hpp"

namespace ema {

namespace {

std::string Extension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace

bool IsSupportedPlotPath(const std::filesystem::path& path) {
  const std::string ext = Extension(path);
  return ext == ".svg" || ext == ".png";
}

void PlotStabilisation(const std::filesystem::path& path, const curvefit::StabilisationDiagram& diagram,
                       const std::vector<curvefit::SelectedPole>& selected) {
  if (!IsSupportedPlotPath(path)) throw UsageError("--plot: expected a .svg or .png file name, got " + path.string());
  const bool svg = Extension(path) == ".svg";
  const std::filesystem::path tmp =
      std::filesystem::temp_directory_path() / ("ema-stab-" + std::to_string(::getpid()) + (svg ? ".svg" : ".png"));

  const double f_lo = diagram.band_lo_hz, f_hi = diagram.band_hi_hz;
  const double y_top = diagram.order_max + 1.0;
  {
    static std::mutex plplot_mutex;  // PLplot keeps global stream state
    std::lock_guard<std::mutex> lock(plplot_mutex);
    plsdev(svg ? "svgcairo" : "pngcairo");
    plsfnam(tmp.string().c_str());
    plspage(0.0, 0.0, 1400, 800, 0, 0);
    plscolbg(255, 255, 255);
    plscol0(1, 0, 0, 0);        // axes, text
    plscol0(2, 0, 150, 0);      // s
    plscol0(3, 0, 90, 220);     // d
    plscol0(4, 150, 0, 180);    // v
    plscol0(5, 230, 140, 0);    // f
    plscol0(6, 160, 160, 160);  // o, x
    plscol0(7, 210, 0, 0);      // selected modes
    plscol0(8, 90, 90, 90);     // sum FRF
    plinit();
    pladv(0);
    plvpor(0.07, 0.91, 0.12, 0.9);
    plwind(f_lo, f_hi, 0.0, y_top);
    plcol0(1);
    plbox("bcnst", 0.0, 0, "bnstv", 0.0, 0);
    pllab("frequency [Hz]", "model order", "");
    plschr(0.0, 0.75);
    plmtex("t", 1.2, 0.0, 0.0,
           "s stable   d freq+damping   v freq+vector   f freq   o new   x impossible (zeta<=0)   -- selected");
    plschr(0.0, 1.0);

    // Mode indicator (sum of |H|) on a log right-hand axis.
    std::vector<double> fx, fy;
    for (int k = 0; k < diagram.frequency_hz.size(); ++k)
      if (diagram.sum_frf[k] > 0.0) fx.push_back(diagram.frequency_hz[k]), fy.push_back(std::log10(diagram.sum_frf[k]));
    if (!fy.empty()) {
      const double lo = *std::min_element(fy.begin(), fy.end()), hi = *std::max_element(fy.begin(), fy.end());
      plwind(f_lo, f_hi, lo - 0.05 * (hi - lo + 1e-12), hi + 0.05 * (hi - lo + 1e-12));
      plcol0(8);
      plline(static_cast<PLINT>(fx.size()), fx.data(), fy.data());
      plbox("", 0.0, 0, "cmstvl", 0.0, 0);
      plmtex("r", 4.0, 0.5, 0.5, "sum |H| (log)");
      plwind(f_lo, f_hi, 0.0, y_top);
    }

    // Selected modes.
    pllsty(2);
    plcol0(7);
    for (const auto& s : selected) {
      const double x[2] = {s.pole.frequency_hz, s.pole.frequency_hz}, y[2] = {0.0, y_top};
      plline(2, x, y);
    }
    pllsty(1);

    // Poles by category.
    plschr(0.0, 0.6);
    const struct {
      char label;
      int colour;
      const char* glyph;
    } kinds[] = {{'o', 6, "o"}, {'f', 5, "f"}, {'v', 4, "v"}, {'d', 3, "d"}, {'s', 2, "s"}};
    for (const auto& kind : kinds) {
      std::vector<double> x, y;
      for (const auto& order : diagram.orders)
        for (const auto& p : order)
          if (p.physical && p.label == kind.label) x.push_back(p.frequency_hz), y.push_back(p.order);
      plcol0(kind.colour);
      if (!x.empty()) plstring(static_cast<PLINT>(x.size()), x.data(), y.data(), kind.glyph);
    }
    std::vector<double> x, y;
    for (const auto& order : diagram.orders)
      for (const auto& p : order)
        if (p.damping_ratio <= 0.0 && p.frequency_hz >= f_lo && p.frequency_hz <= f_hi)
          x.push_back(p.frequency_hz), y.push_back(p.order);
    plcol0(6);
    plschr(0.0, 0.45);
    if (!x.empty()) plstring(static_cast<PLINT>(x.size()), x.data(), y.data(), "x");
    plend();
  }
  std::ifstream in(tmp, std::ios::binary);
  if (!in) throw InputError(path.string(), "the plot could not be rendered");
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  std::filesystem::remove(tmp);
  formats::WriteFileAtomically(path, [&](std::ostream& out) { out.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); });
}

}  // namespace ema
