// Tests of mgn/core: per-item random streams and deterministic parallel_for.
#include <gtest/gtest.h>
#include <mgn/core/error.hpp>
#include <mgn/core/parallel.hpp>
#include <mgn/core/rng.hpp>

#include <atomic>
#include <cmath>
#include <vector>

TEST(Rng, SameSeedAndIndexGiveSameStream) {
  mgn::Rng a(42, 7), b(42, 7), c(42, 8), d(43, 7);
  bool differs_c = false, differs_d = false;
  for (int i = 0; i < 100; ++i) {
    const auto x = a.next_u64();
    EXPECT_EQ(x, b.next_u64());
    differs_c |= x != c.next_u64();
    differs_d |= x != d.next_u64();
  }
  EXPECT_TRUE(differs_c);
  EXPECT_TRUE(differs_d);
}

TEST(Rng, UniformAndNormalMoments) {
  mgn::Rng r(1, 0);
  const int n = 200000;
  double su = 0, sn = 0, sn2 = 0;
  for (int i = 0; i < n; ++i) {
    const double u = r.uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    su += u;
    const double z = r.normal();
    sn += z;
    sn2 += z * z;
  }
  EXPECT_NEAR(su / n, 0.5, 0.005);
  EXPECT_NEAR(sn / n, 0.0, 0.01);
  EXPECT_NEAR(sn2 / n, 1.0, 0.02);
  std::vector<int> counts(5, 0);
  for (int i = 0; i < 50000; ++i) ++counts[r.below(5)];
  for (int c : counts) EXPECT_NEAR(c, 10000, 400);
}

TEST(Parallel, CoversEveryIndexOnceForAnyThreadCount) {
  for (int threads : {1, 2, 3, 8}) {
    std::vector<std::atomic<int>> hits(1001);
    for (auto& h : hits) h = 0;
    mgn::parallel_for(hits.size(), threads, 1, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) ++hits[i];
    });
    for (auto& h : hits) EXPECT_EQ(h.load(), 1);
  }
}

TEST(Parallel, RethrowsWorkerErrorsAndRejectsNegativeThreads) {
  EXPECT_THROW(mgn::parallel_for(100, 2, 1,
                                 [](std::size_t b, std::size_t) {
                                   if (b > 0) throw mgn::InvalidArgument("boom");
                                 }),
               mgn::InvalidArgument);
  EXPECT_THROW(mgn::resolve_num_threads(-1), mgn::InvalidArgument);
  EXPECT_GE(mgn::resolve_num_threads(0), 1);
}
