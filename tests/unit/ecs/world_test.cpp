// Tests for runtime/ecs/world.h: handles and generations, component storage, views, sort_like,
// CommandBuffer, and the debug iteration lock. The churn test checks every view against a
// brute-force std::set model driven by a fixed-seed RNG.
#include "runtime/ecs/world.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

namespace kaskad::ecs {
namespace {

// Each component remembers the entity index it was given to, so tests can check that pools move
// values together with their entities.
struct A {
  std::uint32_t owner = 0;
};
struct B {
  std::uint32_t owner = 0;
  float weight = 0.0f;
};
struct C {
  std::uint32_t owner = 0;
};
struct Tag {};

struct Position {
  float x = 0, y = 0, z = 0;
};

// Long enough to defeat the small-string optimisation, so moves transfer heap buffers.
struct Name {
  std::string first;
  std::string last;
};

// --- Handles -------------------------------------------------------------------------------------

TEST(World, CreateGivesDistinctLiveHandles) {
  World w;
  EXPECT_EQ(w.size(), 0u);
  EXPECT_FALSE(w.alive(kNullEntity));
  const Entity a = w.create();
  const Entity b = w.create();
  const Entity c = w.create();
  EXPECT_TRUE(a.valid());
  EXPECT_NE(a, b);
  EXPECT_NE(b, c);
  EXPECT_NE(a.index, c.index);
  EXPECT_TRUE(w.alive(a) && w.alive(b) && w.alive(c));
  EXPECT_EQ(w.size(), 3u);
}

TEST(World, DestroyBumpsGenerationAndStaleHandleMissesReusedSlot) {
  World w;
  const Entity old = w.create();
  w.emplace<A>(old, A{old.index});
  w.destroy(old);
  EXPECT_FALSE(w.alive(old));
  EXPECT_EQ(w.size(), 0u);
  EXPECT_EQ(w.count<A>(), 0u) << "destroy removes the entity's components";

  const Entity fresh = w.create();  // most recently freed slot first
  ASSERT_EQ(fresh.index, old.index);
  EXPECT_EQ(fresh.generation, old.generation + 1);
  EXPECT_TRUE(w.alive(fresh));
  EXPECT_FALSE(w.alive(old));

  w.emplace<A>(fresh, A{42});
  // The stale handle must not see, remove or destroy the new occupant of its slot.
  EXPECT_FALSE(w.has<A>(old));
  EXPECT_EQ(w.try_get<A>(old), nullptr);
  w.remove<A>(old);
  EXPECT_TRUE(w.has<A>(fresh));
  w.destroy(old);
  EXPECT_TRUE(w.alive(fresh));
  EXPECT_EQ(w.get<A>(fresh).owner, 42u);
  EXPECT_EQ(w.size(), 1u);
}

TEST(World, NullHandleIsNeverAlive) {
  World w;
  w.create();
  EXPECT_FALSE(w.has<A>(kNullEntity));
  EXPECT_EQ(w.try_get<A>(kNullEntity), nullptr);
  w.remove<A>(kNullEntity);
  w.destroy(kNullEntity);
  EXPECT_EQ(w.size(), 1u);
}

TEST(World, ClearDestroysEverythingAndOldHandlesStayStale) {
  World w;
  std::vector<Entity> old;
  for (int i = 0; i < 10; ++i) {
    old.push_back(w.create());
    w.emplace<A>(old.back());
  }
  w.clear();
  EXPECT_EQ(w.size(), 0u);
  EXPECT_EQ(w.count<A>(), 0u);
  for (Entity e : old) EXPECT_FALSE(w.alive(e));
  const Entity e = w.create();
  w.emplace<A>(e);
  for (Entity o : old) EXPECT_FALSE(w.has<A>(o));
  EXPECT_EQ(w.count<A>(), 1u);
}

// --- Components ----------------------------------------------------------------------------------

TEST(World, EmplaceAddsOrReplacesAndReturnsTheStoredValue) {
  World w;
  const Entity e = w.create();
  EXPECT_FALSE(w.has<Position>(e));
  Position& p = w.emplace<Position>(e, 1.0f, 2.0f, 3.0f);  // aggregate built from arguments
  EXPECT_EQ(&p, &w.get<Position>(e));
  EXPECT_EQ(p.y, 2.0f);
  EXPECT_TRUE(w.has<Position>(e));
  EXPECT_EQ(w.count<Position>(), 1u);

  Position& q = w.emplace<Position>(e, Position{4.0f, 5.0f, 6.0f});  // replaces
  EXPECT_EQ(w.count<Position>(), 1u);
  EXPECT_EQ(q.x, 4.0f);
  EXPECT_EQ(w.get<Position>(e).z, 6.0f);
}

TEST(World, RemoveHasGetTryGet) {
  World w;
  const Entity e = w.create();
  const Entity f = w.create();
  w.emplace<A>(e, A{e.index});
  w.emplace<B>(e, B{e.index, 0.5f});
  w.emplace<A>(f, A{f.index});

  const World& cw = w;
  EXPECT_EQ(cw.get<B>(e).weight, 0.5f);
  ASSERT_NE(cw.try_get<A>(f), nullptr);
  EXPECT_EQ(cw.try_get<A>(f)->owner, f.index);
  EXPECT_EQ(w.try_get<B>(f), nullptr);
  EXPECT_EQ(w.try_get<C>(f), nullptr) << "type never used in this world";
  EXPECT_FALSE(w.has<C>(e));

  w.remove<A>(e);  // swaps f's A into e's old slot; f's value must follow
  EXPECT_FALSE(w.has<A>(e));
  EXPECT_TRUE(w.has<B>(e));
  EXPECT_EQ(w.get<A>(f).owner, f.index);
  w.remove<A>(e);  // absent: no-op
  w.remove<C>(e);  // pool never created: no-op
  EXPECT_EQ(w.count<A>(), 1u);
  EXPECT_EQ(w.count<B>(), 1u);
  EXPECT_EQ(w.count<C>(), 0u);
}

TEST(World, StringComponentsSurviveSwapRemoveAndSort) {
  World w;
  std::vector<Entity> es;
  for (int i = 0; i < 64; ++i) {
    const Entity e = w.create();
    es.push_back(e);
    w.emplace<Name>(e, "first name number " + std::to_string(i) + " (long enough for the heap)",
                    "last name " + std::to_string(i * 7) + " also quite long, beyond SSO");
    if (i % 3 == 0) w.emplace<Tag>(e);
  }
  for (int i = 0; i < 64; i += 2) w.remove<Name>(es[i]);  // each removal moves the last Name
  w.sort_like<Tag, Name>();
  w.emplace<Name>(es[1], Name{"replaced", "value"});
  for (int i = 0; i < 64; ++i) {
    if (i % 2 == 0) {
      EXPECT_FALSE(w.has<Name>(es[i]));
    } else if (i == 1) {
      EXPECT_EQ(w.get<Name>(es[i]).first, "replaced");
    } else {
      const Name& n = w.get<Name>(es[i]);
      EXPECT_EQ(n.first, "first name number " + std::to_string(i) + " (long enough for the heap)");
      EXPECT_EQ(n.last, "last name " + std::to_string(i * 7) + " also quite long, beyond SSO");
    }
  }
}

TEST(World, MoveOnlyComponents) {
  World w;
  const Entity e = w.create();
  const Entity f = w.create();
  w.emplace<std::unique_ptr<int>>(e, std::make_unique<int>(7));
  w.emplace<std::unique_ptr<int>>(f, std::make_unique<int>(8));
  w.remove<std::unique_ptr<int>>(e);
  EXPECT_EQ(*w.get<std::unique_ptr<int>>(f), 8);
  CommandBuffer cb;
  cb.emplace<std::unique_ptr<int>>(e, std::make_unique<int>(9));
  cb.flush(w);
  EXPECT_EQ(*w.get<std::unique_ptr<int>>(e), 9);
}

// --- Views ---------------------------------------------------------------------------------------

class ViewTest : public ::testing::Test {
 protected:
  // Entity i has A always, B when i % 2 == 0, C when i % 3 == 0.
  void SetUp() override {
    for (std::uint32_t i = 0; i < 30; ++i) {
      const Entity e = w.create();
      es.push_back(e);
      w.emplace<A>(e, A{e.index});
      if (i % 2 == 0) w.emplace<B>(e, B{e.index, float(i)});
      if (i % 3 == 0) w.emplace<C>(e, C{e.index});
    }
  }
  World w;
  std::vector<Entity> es;
};

TEST_F(ViewTest, OneComponent) {
  std::set<std::uint32_t> seen;
  w.view<A>().each([&](Entity e, A& a) {
    EXPECT_EQ(a.owner, e.index);
    seen.insert(e.index);
  });
  EXPECT_EQ(seen.size(), 30u);
}

TEST_F(ViewTest, TwoAndThreeComponents) {
  std::set<std::uint32_t> two, three;
  w.view<A, B>().each([&](Entity e, A& a, B& b) {
    EXPECT_EQ(a.owner, e.index);
    EXPECT_EQ(b.owner, e.index);
    two.insert(e.index);
  });
  w.view<A, B, C>().each([&](Entity e, A&, B&, C& c) {
    EXPECT_EQ(c.owner, e.index);
    three.insert(e.index);
  });
  std::set<std::uint32_t> want_two, want_three;
  for (std::uint32_t i = 0; i < 30; ++i) {
    if (i % 2 == 0) want_two.insert(es[i].index);
    if (i % 6 == 0) want_three.insert(es[i].index);
  }
  EXPECT_EQ(two, want_two);
  EXPECT_EQ(three, want_three);
}

TEST_F(ViewTest, Exclusion) {
  std::set<std::uint32_t> seen;
  w.view<A>(exclude<B, C>).each([&](Entity e, A&) { seen.insert(e.index); });
  std::set<std::uint32_t> want;
  for (std::uint32_t i = 0; i < 30; ++i)
    if (i % 2 != 0 && i % 3 != 0) want.insert(es[i].index);
  EXPECT_EQ(seen, want);

  int with_b_not_c = 0;
  for (auto [e, a, b] : w.view<A, B>(exclude<C>)) {
    EXPECT_FALSE(w.has<C>(e));
    EXPECT_EQ(a.owner, b.owner);
    ++with_b_not_c;
  }
  EXPECT_EQ(with_b_not_c, 10);  // even, not a multiple of 3: 2,4,8,10,14,16,20,22,26,28
}

TEST_F(ViewTest, EachWithoutEntityParameterMutates) {
  w.view<B>().each([](B& b) { b.weight += 100.0f; });
  EXPECT_EQ(w.get<B>(es[4]).weight, 104.0f);
}

TEST_F(ViewTest, RangeForYieldsReferences) {
  for (auto [e, a, b] : w.view<A, B>()) {
    static_assert(std::is_same_v<decltype(a), A&>);
    static_assert(std::is_same_v<decltype(b), B&>);
    static_assert(std::is_same_v<decltype(e), Entity>);
    b.weight = -1.0f;
    a.owner += 1000;
  }
  EXPECT_EQ(w.get<B>(es[2]).weight, -1.0f);
  EXPECT_EQ(w.get<A>(es[2]).owner, es[2].index + 1000);
  EXPECT_EQ(w.get<A>(es[3]).owner, es[3].index) << "entity without B untouched";
}

TEST_F(ViewTest, ConstWorldGivesConstViews) {
  const World& cw = w;
  int n = 0;
  cw.view<A, B>().each([&](Entity, const A& a, const B& b) {
    EXPECT_EQ(a.owner, b.owner);
    ++n;
  });
  EXPECT_EQ(n, 15);
  for (auto [e, a] : cw.view<A>()) {
    static_assert(std::is_same_v<decltype(a), const A&>);
    EXPECT_EQ(a.owner, e.index);
  }
  // Read-only access to one type through a mutable world.
  for (auto [e, a, b] : w.view<const A, B>()) {
    static_assert(std::is_same_v<decltype(a), const A&>);
    static_assert(std::is_same_v<decltype(b), B&>);
    b.weight = float(a.owner);
  }
  // A type no entity ever had: empty, for const and mutable worlds.
  EXPECT_EQ(cw.view<Position>().size_hint(), 0u);
  int none = 0;
  cw.view<A, Position>().each([&](const A&, const Position&) { ++none; });
  for (auto [e, a] : cw.view<A>(exclude<Position>)) {
    (void)e;
    (void)a;
    ++none;
  }
  EXPECT_EQ(none, 30);
}

TEST_F(ViewTest, ViewMadeBeforeComponentsSeesThem) {
  // A mutable world registers the pools when the view is made, and iteration reads the pools'
  // current contents, so a kept view sees components added after it was made.
  const auto v = w.view<Position, A>();
  w.emplace<Position>(es[0], 1.0f, 1.0f, 1.0f);
  w.emplace<Position>(es[7], 2.0f, 2.0f, 2.0f);
  std::set<std::uint32_t> seen;
  v.each([&](Entity e, Position&, A&) { seen.insert(e.index); });
  EXPECT_EQ(seen, (std::set<std::uint32_t>{es[0].index, es[7].index}));
  int n = 0;
  for (auto [e, p, a] : v) {
    EXPECT_EQ(a.owner, e.index);
    EXPECT_GT(p.x, 0.0f);
    ++n;
  }
  EXPECT_EQ(n, 2);
}

TEST_F(ViewTest, AllowedChangesDuringIteration) {
  // Non-iterated types and excluded types may change; so may values of iterated ones; create() is
  // fine. None of these may trip the debug lock.
  w.view<A>(exclude<Tag>).each([&](Entity e, A&) {
    w.emplace<Tag>(e);
    w.remove<C>(e);
    w.emplace<A>(e, A{7});  // replacement, not a structural change
    w.create();
  });
  EXPECT_EQ(w.count<Tag>(), 30u);
  EXPECT_EQ(w.count<C>(), 0u);
  EXPECT_EQ(w.get<A>(es[5]).owner, 7u);
  EXPECT_EQ(w.size(), 60u);
}

TEST_F(ViewTest, BreakOutOfRangeForReleasesTheLock) {
  int n = 0;
  for (auto [e, a] : w.view<A>()) {
    (void)e;
    (void)a;
    if (++n == 3) break;
  }
  EXPECT_EQ(n, 3);
  // Would fail the debug lock check if the break had leaked the lock.
  w.remove<A>(es[0]);
  w.destroy(es[1]);
  EXPECT_EQ(w.count<A>(), 28u);
}

TEST_F(ViewTest, NestedViewsOverTheSamePool) {
  int pairs = 0;
  w.view<C>().each([&](C&) { w.view<C, A>().each([&](C&, A&) { ++pairs; }); });
  EXPECT_EQ(pairs, 10 * 10);
  w.remove<C>(es[0]);  // both locks released
  EXPECT_EQ(w.count<C>(), 9u);
}

// --- Property test: random churn against a std::set model ----------------------------------------

TEST(WorldProperty, ViewsMatchBruteForceModelUnderChurn) {
  World w;
  std::mt19937 rng(0x5eed);
  std::vector<Entity> live;
  std::map<std::uint32_t, Entity> by_index;
  std::set<std::uint32_t> has_a, has_b, has_c;  // entity indices (the model)
  std::vector<Entity> dead;

  auto pick = [&]() {
    return live[std::uniform_int_distribution<std::size_t>(0, live.size() - 1)(rng)];
  };

  auto check = [&]() {
    ASSERT_EQ(w.size(), live.size());
    ASSERT_EQ(w.count<A>(), has_a.size());
    ASSERT_EQ(w.count<B>(), has_b.size());
    ASSERT_EQ(w.count<C>(), has_c.size());
    std::set<std::uint32_t> got, want;
    auto expect_view = [&](const char* what, auto in) {
      std::set<std::uint32_t> expected;
      for (const auto& [index, e] : by_index)
        if (in(index)) expected.insert(index);
      EXPECT_EQ(got, expected) << what;
      got.clear();
    };
    w.view<A>().each([&](Entity e, A& a) {
      EXPECT_EQ(a.owner, e.index);
      got.insert(e.index);
    });
    expect_view("A", [&](std::uint32_t i) { return has_a.count(i) > 0; });
    w.view<A, B>().each([&](Entity e, A& a, B& b) {
      EXPECT_EQ(a.owner, e.index);
      EXPECT_EQ(b.owner, e.index);
      got.insert(e.index);
    });
    expect_view("A,B", [&](std::uint32_t i) { return has_a.count(i) && has_b.count(i); });
    for (auto [e, a, b, c] : w.view<A, B, C>()) {
      EXPECT_EQ(c.owner, e.index);
      got.insert(e.index);
    }
    expect_view("A,B,C", [&](std::uint32_t i) {
      return has_a.count(i) && has_b.count(i) && has_c.count(i);
    });
    w.view<B>(exclude<A>).each([&](Entity e, B&) { got.insert(e.index); });
    expect_view("B !A", [&](std::uint32_t i) { return has_b.count(i) && !has_a.count(i); });
    for (auto [e, c] : w.view<C>(exclude<A, B>)) got.insert(e.index);
    expect_view("C !A !B", [&](std::uint32_t i) {
      return has_c.count(i) && !has_a.count(i) && !has_b.count(i);
    });
    for (Entity d : dead) ASSERT_FALSE(w.alive(d) || w.has<A>(d) || w.has<B>(d));
  };

  for (int op = 0; op < 5000; ++op) {
    const int r = std::uniform_int_distribution<int>(0, 99)(rng);
    if (live.empty() || r < 15) {
      const Entity e = w.create();
      live.push_back(e);
      by_index[e.index] = e;
    } else if (r < 25) {
      const Entity e = pick();
      w.destroy(e);
      live.erase(std::find(live.begin(), live.end(), e));
      by_index.erase(e.index);
      has_a.erase(e.index);
      has_b.erase(e.index);
      has_c.erase(e.index);
      dead.push_back(e);
    } else if (r < 40) {
      const Entity e = pick();
      w.emplace<A>(e, A{e.index});
      has_a.insert(e.index);
    } else if (r < 55) {
      const Entity e = pick();
      w.emplace<B>(e, B{e.index, 1.0f});
      has_b.insert(e.index);
    } else if (r < 65) {
      const Entity e = pick();
      w.emplace<C>(e, C{e.index});
      has_c.insert(e.index);
    } else if (r < 75) {
      const Entity e = pick();
      w.remove<A>(e);
      has_a.erase(e.index);
    } else if (r < 85) {
      const Entity e = pick();
      w.remove<B>(e);
      has_b.erase(e.index);
    } else if (r < 93) {
      const Entity e = pick();
      w.remove<C>(e);
      has_c.erase(e.index);
    } else if (r < 96) {
      w.sort_like<A, B>();
    } else {
      w.sort_like<C, A>();
    }
    if (op % 20 == 0) check();
  }
  check();
  EXPECT_GT(has_a.size(), 50u) << "the churn should leave a non-trivial world";
}

// --- Aligned-prefix cache (View step 2) ----------------------------------------------------------

// Views remember how far pools are aligned; anything that moves elements must invalidate that,
// while appends must not break it. Values carry their owner, so a stale prefix would show up as a
// mismatched pair.
TEST(WorldAlignment, RemovalInsideARememberedPrefixIsSeen) {
  World w;
  std::vector<Entity> es;
  for (std::uint32_t i = 0; i < 100; ++i) {
    es.push_back(w.create());
    w.emplace<A>(es.back(), A{es.back().index});
    w.emplace<B>(es.back(), B{es.back().index, 0.0f});
  }
  auto expect_pairs = [&](std::size_t want) {
    std::size_t n = 0;
    w.view<A, B>().each([&](Entity e, A& a, B& b) {
      EXPECT_EQ(a.owner, e.index);
      EXPECT_EQ(b.owner, e.index);
      ++n;
    });
    std::size_t m = 0;
    for (auto [e, a, b] : w.view<A, B>()) {
      EXPECT_EQ(a.owner, e.index);
      EXPECT_EQ(b.owner, e.index);
      ++m;
    }
    EXPECT_EQ(n, want);
    EXPECT_EQ(m, want);
  };
  expect_pairs(100);   // remembers a full-length prefix
  w.remove<B>(es[3]);  // B's last element moves to position 3
  expect_pairs(99);
  w.emplace<B>(es[3], B{es[3].index, 0.0f});  // appended at the end: B is now out of order
  expect_pairs(100);
  w.sort_like<A, B>();  // aligned again, remembered by sort_like itself
  expect_pairs(100);
  for (std::uint32_t i = 0; i < 10; ++i) {  // appends keep the remembered prefix valid
    const Entity e = w.create();
    w.emplace<A>(e, A{e.index});
    w.emplace<B>(e, B{e.index, 0.0f});
  }
  expect_pairs(110);
  w.destroy(es[0]);
  expect_pairs(109);
  w.remove<A>(es[50]);
  w.emplace<A>(es[50], A{es[50].index});
  expect_pairs(109);
  const World& cw = w;  // const views read the cache but never write it
  std::size_t n = 0;
  cw.view<A, B>().each([&](Entity e, const A& a, const B& b) {
    EXPECT_EQ(a.owner, e.index);
    EXPECT_EQ(b.owner, e.index);
    ++n;
  });
  EXPECT_EQ(n, 109u);
  w.clear();
  expect_pairs(0);
}

// --- sort_like -----------------------------------------------------------------------------------

TEST(WorldSortLike, AlignsFollowerToLeaderAndPreservesContents) {
  World w;
  std::mt19937 rng(7);
  std::vector<Entity> es;
  for (std::uint32_t i = 0; i < 5000; ++i) {  // more than one sparse page
    const Entity e = w.create();
    es.push_back(e);
    w.emplace<A>(e, A{e.index});
    w.emplace<B>(e, B{e.index, float(i)});
  }
  // Churn: removing and re-adding B in random order scrambles B relative to A.
  for (int k = 0; k < 3000; ++k) {
    const Entity e = es[std::uniform_int_distribution<std::size_t>(0, es.size() - 1)(rng)];
    if (w.has<B>(e)) {
      w.remove<B>(e);
    } else {
      w.emplace<B>(e, B{e.index, float(e.index)});
    }
  }
  for (Entity e : es)
    if (!w.has<B>(e)) w.emplace<B>(e, B{e.index, float(e.index)});  // every A has a B again
  const auto a_before = w.entities<A>();
  const std::vector<Entity> a_order(a_before.begin(), a_before.end());
  ASSERT_FALSE(std::equal(a_order.begin(), a_order.end(), w.entities<B>().begin()))
      << "churn should have misaligned the pools";

  w.sort_like<A, B>();
  const auto b = w.entities<B>();
  const auto a = w.entities<A>();
  ASSERT_EQ(b.size(), a.size());
  EXPECT_TRUE(std::equal(a.begin(), a.end(), b.begin())) << "B follows A position by position";
  EXPECT_TRUE(std::equal(a_order.begin(), a_order.end(), a.begin())) << "leader untouched";
  for (Entity e : es) {
    EXPECT_EQ(w.get<B>(e).owner, e.index) << "values moved with their entities";
    EXPECT_EQ(w.get<B>(e).weight, float(e.index));
  }
}

TEST(WorldSortLike, SharedEntitiesComeFirstWhenLeaderHasMore) {
  World w;
  std::vector<Entity> es;
  for (std::uint32_t i = 0; i < 100; ++i) es.push_back(w.create());
  for (std::uint32_t i = 100; i-- > 0;) w.emplace<A>(es[i], A{es[i].index});  // reverse order
  for (std::uint32_t i = 0; i < 100; ++i)
    if (i % 4 == 0 || i >= 90) w.emplace<C>(es[i], C{es[i].index});
  w.sort_like<A, C>();
  // C's entities that also have A (all of them) now follow A's order: descending index.
  const auto c = w.entities<C>();
  ASSERT_EQ(c.size(), 33u);
  for (std::size_t k = 1; k < c.size(); ++k) EXPECT_GT(c[k - 1].index, c[k].index);
  for (Entity e : c) EXPECT_EQ(w.get<C>(e).owner, e.index);
}

// --- CommandBuffer -------------------------------------------------------------------------------

TEST(CommandBuffer, ChangesAreDeferredUntilFlush) {
  World w;
  const Entity e = w.create();
  const Entity f = w.create();
  w.emplace<A>(f, A{f.index});
  CommandBuffer cb;
  cb.emplace<A>(e, A{e.index});
  cb.remove<A>(f);
  cb.destroy(f);
  const Entity p = cb.create();
  cb.emplace<B>(p, B{0, 2.5f});
  cb.emplace<C>(p);
  EXPECT_EQ(cb.size(), 6u);
  EXPECT_FALSE(w.alive(p)) << "placeholders are not entities";
  EXPECT_FALSE(w.has<A>(e));
  EXPECT_TRUE(w.has<A>(f));
  EXPECT_EQ(w.size(), 2u);

  cb.flush(w);
  EXPECT_TRUE(cb.empty());
  EXPECT_TRUE(w.has<A>(e));
  EXPECT_FALSE(w.alive(f));
  EXPECT_EQ(w.size(), 2u);
  EXPECT_EQ(w.count<B>(), 1u);
  EXPECT_EQ(w.count<C>(), 1u);
  w.view<B, C>().each([](B& b, C&) { EXPECT_EQ(b.weight, 2.5f); });
}

TEST(CommandBuffer, AppliesInRecordingOrder) {
  World w;
  const Entity e = w.create();
  CommandBuffer cb;
  cb.emplace<A>(e, A{1});
  cb.emplace<A>(e, A{2});
  cb.remove<B>(e);
  cb.emplace<B>(e, B{3, 0.0f});
  cb.flush(w);
  EXPECT_EQ(w.get<A>(e).owner, 2u);
  EXPECT_EQ(w.get<B>(e).owner, 3u);
}

TEST(CommandBuffer, DestroyDuringIteration) {
  World w;
  for (std::uint32_t i = 0; i < 100; ++i) {
    const Entity e = w.create();
    w.emplace<A>(e, A{i});
    w.emplace<B>(e, B{i, 0.0f});
  }
  CommandBuffer cb;
  w.view<A, B>().each([&](Entity e, A& a, B&) {
    if (a.owner % 2 == 0) {
      cb.destroy(e);
      const Entity child = cb.create();
      cb.emplace<C>(child, C{a.owner});
    }
  });
  for (auto [e, a] : w.view<A>())
    if (a.owner % 5 == 0) cb.remove<A>(e);
  EXPECT_EQ(w.size(), 100u);
  cb.flush(w);
  EXPECT_EQ(w.size(), 100u);     // 50 destroyed, 50 created
  EXPECT_EQ(w.count<A>(), 40u);  // odd owners not divisible by 5: 50 - 10
  EXPECT_EQ(w.count<C>(), 50u);
  w.view<A>().each([](A& a) { EXPECT_TRUE(a.owner % 2 == 1 && a.owner % 5 != 0); });
}

TEST(CommandBuffer, CommandsOnEntitiesDestroyedBeforeFlushAreSkipped) {
  World w;
  const Entity e = w.create();
  const Entity f = w.create();
  CommandBuffer cb;
  cb.emplace<A>(e, A{1});
  cb.destroy(e);
  cb.destroy(f);
  cb.emplace<A>(f, A{2});  // f dies in this buffer before this command runs
  const Entity p = cb.create();
  cb.destroy(p);
  cb.emplace<B>(p);                  // its created entity is already gone
  w.destroy(e);                      // dies before the flush
  const Entity reused = w.create();  // takes e's slot with a new generation
  ASSERT_EQ(reused.index, e.index);

  cb.flush(w);
  EXPECT_FALSE(w.alive(e));
  EXPECT_FALSE(w.alive(f));
  EXPECT_TRUE(w.alive(reused));
  EXPECT_FALSE(w.has<A>(reused)) << "stale command must not hit the slot's new occupant";
  EXPECT_EQ(w.count<A>(), 0u);
  EXPECT_EQ(w.count<B>(), 0u);
  EXPECT_EQ(w.size(), 1u);
}

TEST(CommandBuffer, FlushIsReusable) {
  World w;
  CommandBuffer cb;
  for (int round = 0; round < 3; ++round) {
    const Entity p = cb.create();
    cb.emplace<A>(p, A{std::uint32_t(round)});
    cb.flush(w);
  }
  EXPECT_EQ(w.count<A>(), 3u);
}

// --- Precondition failures -----------------------------------------------------------------------

TEST(WorldDeathTest, GetOnStaleHandleAborts) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  World w;
  const Entity e = w.create();
  w.emplace<A>(e);
  w.destroy(e);
  const Entity reused = w.create();
  w.emplace<A>(reused);
  EXPECT_DEATH(w.get<A>(e), "precondition failed in get: entity 0 \\(generation 0\\) is not alive");
  EXPECT_DEATH(w.get<B>(reused), "has no '.*B' component");
  EXPECT_DEATH(w.emplace<B>(e), "precondition failed in emplace: .*not alive");
}

TEST(WorldDeathTest, PlaceholderFromAnotherBufferAborts) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  CommandBuffer a, b;
  const Entity p = a.create();
  EXPECT_DEATH(b.emplace<A>(p), "another CommandBuffer");
}

TEST(WorldDeathTest, StructuralChangeOfIteratedPoolAborts) {
#ifdef NDEBUG
  GTEST_SKIP() << "iteration locks are checked only in debug builds (NDEBUG is defined)";
#else
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  World w;
  const Entity e = w.create();
  const Entity f = w.create();
  w.emplace<A>(e);
  w.emplace<B>(e);
  w.emplace<B>(f);
  EXPECT_DEATH(w.view<A>().each([&](A&) { w.emplace<A>(f); }),
               "precondition failed in emplace: cannot add '.*A' .*use a CommandBuffer");
  EXPECT_DEATH((w.view<A, B>().each([&](Entity x, A&, B&) { w.remove<B>(x); })),
               "precondition failed in remove: .*B");
  EXPECT_DEATH(
      {
        for (auto [x, b] : w.view<B>()) w.destroy(x);
      },
      "precondition failed in destroy: .*use a CommandBuffer");
  EXPECT_DEATH((w.view<B>().each([&](B&) { w.sort_like<A, B>(); })), "cannot reorder");
  EXPECT_DEATH(w.view<B>().each([&](B&) { w.clear(); }), "cannot clear");
  // The same changes are fine once the loop is over.
  w.view<A>().each([](A&) {});
  w.emplace<A>(f);
  w.destroy(e);
  EXPECT_EQ(w.count<A>(), 1u);
#endif
}

}  // namespace
}  // namespace kaskad::ecs
