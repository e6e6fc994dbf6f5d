// The supernodal factorisation's ordering kept per sparsity pattern (sparse_factor.hpp).
#include "sparse_factor.hpp"

#ifdef EMA_HAVE_CHOLMOD
#include <cstdint>
#include <deque>
#include <mutex>
#include <vector>

namespace ema::model::detail {
namespace {

// A sparsity pattern: its size, entries and an FNV-1a hash of its column starts and row indices.
// Two patterns with the same key and different entries would share an ordering — a worse fill,
// never a wrong factor.
struct PatternKey {
  Eigen::Index n = 0, nonzeros = 0;
  std::uint64_t hash = 0;
  bool operator==(const PatternKey&) const = default;
};

PatternKey PatternKeyOf(const Eigen::SparseMatrix<double>& a) {
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&h](std::int64_t v) {
    h ^= static_cast<std::uint64_t>(v);
    h *= 1099511628211ull;
  };
  for (Eigen::Index j = 0; j <= a.outerSize(); ++j) mix(a.outerIndexPtr()[j]);
  for (Eigen::Index k = 0; k < a.nonZeros(); ++k) mix(a.innerIndexPtr()[k]);
  return {a.rows(), a.nonZeros(), h};
}

// The last few patterns' orderings (a diagnosis meets one or two: with and without the test's
// sensors' masses at nodes that hold none).
class OrderingCache {
 public:
  bool Find(const PatternKey& key, std::vector<int>* perm) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [k, p] : entries_)
      if (k == key) return *perm = p, true;
    return false;
  }
  void Keep(const PatternKey& key, std::vector<int> perm) {
    std::lock_guard<std::mutex> lock(mutex_);
    entries_.emplace_back(key, std::move(perm));
    if (entries_.size() > 4) entries_.pop_front();
  }

 private:
  std::mutex mutex_;
  std::deque<std::pair<PatternKey, std::vector<int>>> entries_;
};

OrderingCache& Orderings() {
  static OrderingCache cache;
  return cache;
}

}  // namespace

void SupernodalLlt::Factorise(const Eigen::SparseMatrix<double>& a) {
  if (a.isCompressed() && a.rows() > 0) {
    const PatternKey key = PatternKeyOf(a);
    std::vector<int> perm;
    cholmod_common& common = cholmod();  // CholmodSupernodalLLT keeps its member private
    if (m_cholmodFactor) {
      cholmod_free_factor(&m_cholmodFactor, &common);
      m_cholmodFactor = nullptr;
    }
    cholmod_sparse view = Eigen::viewAsCholmod(a.selfadjointView<Eigen::Lower>());
    if (Orderings().Find(key, &perm)) {
      // The ordering given: CHOLMOD skips its own (METIS, AMD) and only builds the supernodes.
      const int methods = common.nmethods, ordering = common.method[0].ordering;
      common.nmethods = 1;
      common.method[0].ordering = CHOLMOD_GIVEN;
      m_cholmodFactor = cholmod_analyze_p(&view, perm.data(), nullptr, 0, &common);
      common.nmethods = methods;
      common.method[0].ordering = ordering;
    } else {
      m_cholmodFactor = cholmod_analyze(&view, &common);
      if (m_cholmodFactor && m_cholmodFactor->Perm) {
        const int* p = static_cast<const int*>(m_cholmodFactor->Perm);
        Orderings().Keep(key, std::vector<int>(p, p + m_cholmodFactor->n));
      }
    }
    m_isInitialized = true;
    m_info = m_cholmodFactor ? Eigen::Success : Eigen::InvalidInput;
    m_analysisIsOk = m_cholmodFactor != nullptr;
    m_factorizationIsOk = false;
    if (m_analysisIsOk) factorize(a);
    return;
  }
  compute(a);
}

}  // namespace ema::model::detail
#endif
