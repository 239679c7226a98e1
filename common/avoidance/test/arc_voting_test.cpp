// Arc voting on synthetic grids with known answers.
#include "avoidance/arc_voting.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace rover::avoidance {
namespace {

constexpr double kDeg = M_PI / 180.0;

// A 12 m x 12 m grid of safe cells (goodness 0.9) centred on the origin, 0.2 m cells.
Grid Open() { return Grid::Filled(-6.0, -6.0, 0.2, 60, 60, CellClass::kSafe, 0.9f); }

// Cells whose centres lie in [x0, x1] x [y0, y1] unknown (never seen).
void MarkUnknown(Grid* g, double x0, double x1, double y0, double y1) {
  for (double x = x0 + 0.1; x < x1; x += 0.2)
    for (double y = y0 + 0.1; y < y1; y += 0.2) g->state[g->IndexAt(x, y)] = CellClass::kUnknown;
}

// A wall of unsafe cells across x = wall_x, from y = y0 to y1.
void Wall(Grid* g, double wall_x, double y0, double y1) {
  for (double y = y0; y <= y1; y += 0.1) g->Paint(wall_x, y, 0.25, CellClass::kUnsafe, 0.0f, 0.4f);
}

TEST(Sweep, CountsCellsOutsideTheStandingFootprint) {
  const Grid g = Open();
  Footprint fp;  // 1.6 x 1.4
  const Pose2 p{0, 0, 0};
  // Standing still: every cell under the body is exempt, nothing is counted.
  EXPECT_EQ(SweepFootprint(g, fp, {p}, p, 0.5).cells, 0);
  // 0.6 m ahead: the new strip is 0.6 m (3 cells) plus the half-cell border, 1.4 m wide.
  const auto path = SamplePath(p, 0.0, 0.6, 0.0);
  const Sweep s = SweepFootprint(g, fp, path, p, 0.5);
  EXPECT_GE(s.cells, 3 * 7);
  EXPECT_LE(s.cells, 5 * 9 + 2 * 5);
  EXPECT_EQ(s.unsafe, 0);
  EXPECT_NEAR(s.min_goodness, 0.9, 1e-6);
}

TEST(Sweep, HiddenGroundWithinTheReachCountsWhereTheBodyComesNearer) {
  // Unseen ground 1 m across whose near edge (y = 0.8) lies 0.1 m beside the body's left
  // side (y = 0.7), ahead of it (x from 1.0; cell centres at odd tenths): a rock there
  // could reach into the safe cells beside it.
  Grid g = Open();
  MarkUnknown(&g, 1.0, 2.0, 0.8, 1.8);
  Footprint fp;  // 1.6 x 1.4
  const Pose2 p{0, 0, 0};
  const auto ahead = SamplePath(p, 0.0, 0.6, 0.0);  // the front reaches x = 1.4, the side stays at y = 0.7
  // Under the footprint grown by half a cell (to y = 0.8) nothing is unknown.
  const Sweep plain = SweepFootprint(g, fp, ahead, p, 0.0, 0.6);
  EXPECT_EQ(plain.unknown, 0);
  EXPECT_EQ(plain.hidden, 0);
  // 0.05 m more (to y = 0.85) reaches no cell centre either.
  EXPECT_EQ(SweepFootprint(g, fp, ahead, p, 0.0, 0.6, 0.05).hidden, 0);
  // 0.25 m more (to y = 1.05, reached by 0.35 m growth in all): the first row counts where
  // the front comes nearer to it than where the rover stands (x = 1.3, 1.5, 1.7; the cell at
  // x = 1.1 lies within that growth of the standing body already), and only as hidden
  // ground, not as unknown.
  const Sweep near = SweepFootprint(g, fp, ahead, p, 0.0, 0.6, 0.25);
  EXPECT_EQ(near.hidden, 3);
  EXPECT_EQ(near.unknown, 0);
  EXPECT_NEAR(near.hidden_y, 0.9, 1e-9);
  // Driving straight away from the same ground (backing up) brings the body nearer to none
  // of it.
  EXPECT_EQ(SweepFootprint(g, fp, SamplePath(p, 0.0, -0.3, 0.0), p, 0.0, 0.6, 0.25).hidden, 0);
  // Ground too narrow to hide a rock (one row of cells) counts at no reach.
  Grid strip = Open();
  MarkUnknown(&strip, 1.0, 2.0, 0.8, 1.0);
  EXPECT_EQ(SweepFootprint(strip, fp, ahead, p, 0.0, 0.6, 0.25).hidden, 0);
}

TEST(Grid, MarkTurnKnownLetsAWholeTurnInPlaceSweepOnlyKnownGround) {
  Grid none = Grid::Filled(-6.0, -6.0, 0.2, 60, 60, CellClass::kUnknown, 0.0f);
  Footprint body;  // 1.6 x 1.4
  Footprint vote = body;
  vote.length_m += 0.2;  // 0.1 m larger all round, as the executor's vote
  vote.width_m += 0.2;
  const Pose2 p{0.05, -0.03, 0.3};
  std::vector<Pose2> turn;
  for (int a = 0; a <= 72; ++a) turn.push_back({p.x, p.y, p.yaw + a * (2.0 * M_PI / 72.0)});
  // The ring round the body (0.5 m) leaves the corners of the larger footprint's turn unseen.
  Grid ring = none;
  ring.MarkKnown(body, p, 0.5);
  EXPECT_GT(SweepFootprint(ring, vote, turn, p, 0.0).unknown, 0);
  // The whole turn's ground known: nothing the turn sweeps is unknown ...
  Grid turned = none;
  EXPECT_GT(turned.MarkTurnKnown(vote, p), 0);
  EXPECT_EQ(SweepFootprint(turned, vote, turn, p, 0.0).unknown, 0);
  // ... and nothing beyond it is known: the disc out to the corner, 1.345 m, grown by half a cell.
  const double r = std::hypot(1.0, 0.9);
  for (int i = 0; i < turned.rows; ++i)
    for (int j = 0; j < turned.cols; ++j) {
      const double d = std::hypot(turned.CellCentreX(i) - p.x, turned.CellCentreY(j) - p.y);
      const bool known = turned.state[static_cast<std::size_t>(i) * turned.cols + j] != CellClass::kUnknown;
      if (d > r + 0.1 + 1e-9) {
        EXPECT_FALSE(known) << i << "," << j;
      }
      if (d < r) {
        EXPECT_TRUE(known) << i << "," << j;
      }
    }
}

TEST(Sweep, FindsTheWorstUnsafeCellAndTheBlindRing) {
  Grid g = Open();
  g.Paint(1.2, 0.0, 0.15, CellClass::kUnsafe, 0.0f, 0.35f);
  g.Paint(1.2, 0.4, 0.15, CellClass::kUnsafe, 0.0f, 0.45f);
  Footprint fp;
  const Pose2 p{0, 0, 0};
  const Sweep s = SweepFootprint(g, fp, SamplePath(p, 0.0, 0.6, 0.0), p, 0.5);
  EXPECT_GT(s.unsafe, 0);
  EXPECT_NEAR(s.worst_step_m, 0.45, 1e-6);
  EXPECT_NEAR(s.worst_x, 1.2, 0.15);
  EXPECT_NEAR(s.worst_y, 0.4, 0.15);
  EXPECT_GE(s.first_unsafe_pose, 0);
  // Unknown ahead: inside the 0.5 m blind ring it is not counted as unknown, beyond it is.
  Grid u = Grid::Filled(-6.0, -6.0, 0.2, 60, 60, CellClass::kUnknown, 0.0f);
  const Sweep near = SweepFootprint(u, fp, SamplePath(p, 0.0, 0.3, 0.0), p, 0.5);
  EXPECT_EQ(near.unknown, 0);
  EXPECT_GT(near.blind_unknown, 0);
  const Sweep far = SweepFootprint(u, fp, SamplePath(p, 0.0, 0.9, 0.0), p, 0.5);
  EXPECT_GT(far.unknown, 0);
  // Off the grid counts as unknown.
  const Pose2 edge{5.5, 0, 0};
  EXPECT_GT(SweepFootprint(Open(), fp, SamplePath(edge, 0.0, 0.6, 0.0), edge, 0.0).outside, 0);
}

// A rock cell right at the body's side (its centre on the side line, within the half-cell
// border that counts as standing on it): driving straight past it or away from it is allowed,
// but a turn in place that swings the side toward it is not, nor an arc to the left, whose
// turn swings the right side out into it.
TEST(Sweep, AnUnsafeCellAtTheBodysEdgeMayNotBeApproached) {
  Grid g = Open();
  const int k = g.IndexAt(0.1, 0.75);  // the cell centred at (0.1, 0.7)
  ASSERT_GE(k, 0);
  g.state[static_cast<std::size_t>(k)] = CellClass::kUnsafe;
  g.goodness[static_cast<std::size_t>(k)] = 0.0f;
  g.step_m[static_cast<std::size_t>(k)] = 0.4f;
  const double cx = g.CellCentreX(k / g.cols), cy = g.CellCentreY(k % g.cols);
  Footprint fp;
  const Pose2 p{0, 0, 0};
  const double out = fp.Outside(p, cx, cy);
  ASSERT_GT(out, -0.1);
  ASSERT_LE(out, 0.1) << "the cell lies in the border counted as under the standing body";
  EXPECT_NEAR(fp.Outside(p, 0.0, 1.0), 0.3, 1e-9);
  EXPECT_NEAR(fp.Outside(p, 0.0, 0.0), -0.7, 1e-9);
  // Straight on past it, or back: allowed.
  EXPECT_EQ(SweepFootprint(g, fp, SamplePath(p, 0.0, 0.6, 0.0), p, 0.5).unsafe, 0);
  EXPECT_EQ(SweepFootprint(g, fp, SamplePath(p, 0.0, -0.3, 0.0), p, 0.5).unsafe, 0);
  // A turn in place to the right (the side ahead of the centre swings toward it), or an arc
  // toward it: the body comes nearer.
  const Sweep turn = SweepFootprint(g, fp, SamplePath(p, 18.0 * kDeg, 0.0, 0.0), p, 0.5);
  EXPECT_EQ(turn.unsafe, 1);
  EXPECT_NEAR(turn.worst_step_m, 0.4, 1e-6);
  EXPECT_NEAR(turn.worst_x, cx, 1e-9);
  EXPECT_NEAR(turn.worst_y, cy, 1e-9);
  EXPECT_GT(turn.first_unsafe_pose, 0);
  EXPECT_EQ(SweepFootprint(g, fp, SamplePath(p, 0.0, 0.6, -0.5), p, 0.5).unsafe, 1);
  // The same cell well under the body (a false rating where the rover stands) pins nothing.
  Grid h = Open();
  h.state[static_cast<std::size_t>(h.IndexAt(0.1, 0.3))] = CellClass::kUnsafe;
  EXPECT_EQ(SweepFootprint(h, fp, SamplePath(p, 18.0 * kDeg, 0.0, 0.0), p, 0.5).unsafe, 0);
}

TEST(Grid, DistrustEdgesKeepsTheInsideOfARock) {
  Grid g = Grid::Filled(0, 0, 0.2, 20, 20, CellClass::kUnknown, 0.0f);
  g.Paint(2.0, 2.0, 1.2, CellClass::kSafe, 0.9f, 0.0f);   // the seen patch
  g.Paint(2.0, 2.0, 0.35, CellClass::kUnsafe, 0.0f, 0.4f);  // a rock inside it
  g.Paint(2.0, 0.9, 0.15, CellClass::kUnsafe, 0.0f, 0.4f);  // a false one on the seen edge
  const int changed = g.DistrustEdges();
  EXPECT_GE(changed, 1);
  EXPECT_EQ(g.state[g.IndexAt(2.0, 2.0)], CellClass::kUnsafe);
  EXPECT_EQ(g.state[g.IndexAt(2.1, 0.9)], CellClass::kUnknown);
}

// A rock whose top took no points: unknown ground 0.6 m across (a 3 x 3 block of cells)
// inside it, and its flank round that seen but read far low (0.14 m, safe: a patch without
// its highest part). Every flank cell beside the block reading half the 0.25 m limit or more
// becomes unsafe; the same reading beside a speck of unknown (no room for a rock's top),
// a lower one (0.10 m) beside such a block, and one a cell further out keep their rating.
TEST(Grid, MarkFlanksOfHiddenGroundMakesTheFlankRoundAnUnseenTopUnsafe) {
  Grid g = Open();
  auto set = [&](double x, double y, CellClass s, float step) {
    const std::size_t k = static_cast<std::size_t>(g.IndexAt(x, y));
    g.state[k] = s;
    g.step_m[k] = step;
    g.goodness[k] = s == CellClass::kUnknown ? 0.0f : 1.0f - step / 0.25f;
  };
  // The rock at (1.9, 1.3): its flank (the 5 x 5 block round it, less its corners), its top.
  for (int di = -2; di <= 2; ++di)
    for (int dj = -2; dj <= 2; ++dj)
      if (std::abs(di) + std::abs(dj) < 4) set(1.9 + 0.2 * di, 1.3 + 0.2 * dj, CellClass::kSafe, 0.14f);
  for (int di = -1; di <= 1; ++di)
    for (int dj = -1; dj <= 1; ++dj) set(1.9 + 0.2 * di, 1.3 + 0.2 * dj, CellClass::kUnknown, 0.0f);
  set(1.9, 1.3 + 0.6, CellClass::kCaution, 0.20f);  // beside the flank, not the top
  // A speck of unknown amid 0.14 m cells (sand the matcher missed beside a cobble).
  for (int di = -1; di <= 1; ++di)
    for (int dj = -1; dj <= 1; ++dj) set(-2.1 + 0.2 * di, -1.9 + 0.2 * dj, CellClass::kSafe, 0.14f);
  set(-2.1, -1.9, CellClass::kUnknown, 0.0f);
  // Unknown ground as wide, with low cells beside it (a hollow, or ground out of view).
  for (int di = -2; di <= 2; ++di)
    for (int dj = -2; dj <= 2; ++dj) set(-2.1 + 0.2 * di, 2.5 + 0.2 * dj, CellClass::kSafe, 0.10f);
  for (int di = -1; di <= 1; ++di)
    for (int dj = -1; dj <= 1; ++dj) set(-2.1 + 0.2 * di, 2.5 + 0.2 * dj, CellClass::kUnknown, 0.0f);

  // A step whose body corner sweeps the flank: clear before, into the rock after.
  const Footprint fp;
  const Pose2 here{0.4, 0.15, 0.0};  // its right front corner ends at (1.8, 0.85), by the flank
  const auto path = SamplePath(here, 0.0, 0.6, 0.0);
  const Sweep before = SweepFootprint(g, fp, path, here, 0.0);
  EXPECT_EQ(before.unsafe, 0);

  EXPECT_EQ(g.MarkFlanksOfHiddenGround(0.6, 0.125), 12);  // the 16 round the top, less its 4 corners
  EXPECT_EQ(g.state[g.IndexAt(1.9 + 0.4, 1.3)], CellClass::kUnsafe);
  EXPECT_EQ(g.state[g.IndexAt(1.9 - 0.2, 1.3 - 0.4)], CellClass::kUnsafe);
  EXPECT_FLOAT_EQ(g.goodness[g.IndexAt(1.9 + 0.4, 1.3)], 0.0f);
  EXPECT_FLOAT_EQ(g.step_m[g.IndexAt(1.9 + 0.4, 1.3)], 0.14f);  // its reading kept
  EXPECT_EQ(g.state[g.IndexAt(1.9, 1.3)], CellClass::kUnknown);  // the top stays unknown
  EXPECT_EQ(g.state[g.IndexAt(1.9, 1.3 + 0.6)], CellClass::kCaution);
  EXPECT_EQ(g.state[g.IndexAt(-2.1 + 0.2, -1.9)], CellClass::kSafe);
  EXPECT_EQ(g.state[g.IndexAt(-2.1 + 0.4, 2.5)], CellClass::kSafe);
  EXPECT_EQ(g.MarkFlanksOfHiddenGround(0.6, 0.125), 0);  // nothing left to mark
  EXPECT_EQ(g.MarkFlanksOfHiddenGround(0.0, 0.125), 0);  // off

  const Sweep after = SweepFootprint(g, fp, path, here, 0.0);
  EXPECT_GT(after.unsafe, 0);
}

TEST(ArcVoting, OpenGroundDrivesStraightAtTheGoal) {
  const Choice c = VoteArcs(Open(), {0, 0, 0}, 4.0, 0.0, VoteOptions{});
  ASSERT_TRUE(c.found);
  EXPECT_EQ(c.best.kind, Candidate::Kind::kArc);
  EXPECT_DOUBLE_EQ(c.best.curvature_per_m, 0.0);
  EXPECT_DOUBLE_EQ(c.best.distance_m, 0.6);
  EXPECT_GE(c.candidates.size(), 23u);  // 21 arcs and 2 turns
}

TEST(ArcVoting, GoalToTheRightCurvesOrTurnsRight) {
  const Choice c = VoteArcs(Open(), {0, 0, 0}, 2.0, 2.0, VoteOptions{});
  ASSERT_TRUE(c.found);
  const double heading_change = c.best.kind == Candidate::Kind::kTurn ? c.best.turn_rad
                                                                      : c.best.curvature_per_m * c.best.distance_m;
  EXPECT_GT(heading_change, 5 * kDeg);
}

TEST(ArcVoting, ShortStepAtTheGoal) {
  const Choice c = VoteArcs(Open(), {0, 0, 0}, 0.4, 0.0, VoteOptions{});
  ASSERT_TRUE(c.found);
  EXPECT_NEAR(c.best.distance_m, 0.4, 1e-9);
}

// Safe ground that is a little rougher straight ahead (a cobble, goodness 0.5 against 0.9
// round it): GESTALT's vote, every difference counting, weaves round it; with
// good_enough at the caution level (0.4) safe ground ranks alike and the rover drives at the
// goal. Caution ground (goodness 0.2) is still steered round.
TEST(ArcVoting, SafeGroundGoodEnoughRanksAlikeAndTheGoalDecides) {
  auto cobble = [](CellClass state, float goodness) {
    Grid g = Open();
    g.Paint(2.6, 0.0, 0.25, state, goodness, 0.05f);
    return g;
  };
  auto heading_change = [](const Candidate& c) {
    return c.kind == Candidate::Kind::kTurn ? c.turn_rad : c.curvature_per_m * c.distance_m;
  };
  const Grid cobbles = cobble(CellClass::kSafe, 0.5f);
  const Choice weave = VoteArcs(cobbles, {0, 0, 0}, 8.0, 0.0, VoteOptions{});
  ASSERT_TRUE(weave.found);
  EXPECT_GT(std::abs(heading_change(weave.best)), 1e-3) << "GESTALT's vote steers off the rougher safe cobble";
  VoteOptions enough;
  enough.good_enough = 0.4;
  const Choice straight = VoteArcs(cobbles, {0, 0, 0}, 8.0, 0.0, enough);
  ASSERT_TRUE(straight.found);
  EXPECT_EQ(straight.best.kind, Candidate::Kind::kArc);
  EXPECT_DOUBLE_EQ(straight.best.curvature_per_m, 0.0);
  EXPECT_NEAR(straight.best.goodness, 0.4, 1e-6);
  const Choice caution = VoteArcs(cobble(CellClass::kCaution, 0.2f), {0, 0, 0}, 8.0, 0.0, enough);
  ASSERT_TRUE(caution.found);
  EXPECT_GT(std::abs(heading_change(caution.best)), 1e-3) << "caution ground still weighs";
  VoteOptions bad;
  bad.good_enough = 0.0;
  EXPECT_THROW(VoteArcs(Open(), {0, 0, 0}, 1, 0, bad), std::invalid_argument);
}

// A plan whose cost to go falls 1.5 a metre (ground it prices above seen safe ground): the
// goal vote is scaled by the best progress, so an arc off the way scores less than the arc
// along it. Divided by the look-ahead alone, both reached the top vote (1), and only the
// goodness told them apart.
TEST(ArcVoting, TheGoalVoteIsScaledByTheBestProgressNotCappedAtTheLookAhead) {
  struct Costly final : GoalDistance {
    double DistanceAt(double x, double y) const override { return 1.5 * std::hypot(10.0 - x, y); }
  } costly;
  VoteOptions o;
  o.goal_distance = &costly;
  const Choice c = VoteArcs(Open(), {0, 0, 0}, 10.0, 0.0, o);
  ASSERT_TRUE(c.found);
  const Candidate* straight = nullptr;
  const Candidate* off = nullptr;
  for (const auto& k : c.candidates) {
    if (k.kind != Candidate::Kind::kArc) continue;
    if (k.curvature_per_m == 0.0) straight = &k;
    if (std::abs(k.curvature_per_m - 0.2) < 1e-9) off = &k;
  }
  ASSERT_TRUE(straight && off);
  EXPECT_GT(off->progress_m, o.lookahead_m) << "the gentle arc alone would have reached the top vote";
  EXPECT_DOUBLE_EQ(straight->goal, 1.0);
  EXPECT_LT(off->goal, 0.995);
  EXPECT_GT(straight->vote, off->vote);
}

TEST(ArcVoting, RockInTheStepVetoesStraightAndNamesIt) {
  Grid g = Open();
  g.Paint(1.3, 0.0, 0.3, CellClass::kUnsafe, 0.0f, 0.38f);
  const Choice c = VoteArcs(g, {0, 0, 0}, 5.0, 0.0, VoteOptions{});
  const Candidate* straight = nullptr;
  for (const auto& k : c.candidates)
    if (k.kind == Candidate::Kind::kArc && k.curvature_per_m == 0.0) straight = &k;
  ASSERT_NE(straight, nullptr);
  EXPECT_TRUE(straight->vetoed);
  EXPECT_NE(straight->why.find("step 0.38 m at 1."), std::string::npos) << straight->why;
  ASSERT_TRUE(c.found);
  EXPECT_FALSE(c.best.kind == Candidate::Kind::kArc && c.best.curvature_per_m == 0.0);
  EXPECT_EQ(c.best.step_sweep.unsafe, 0);
}

// A small rock the map reads at 85 % of a 0.25 m step limit (0.2125 m: caution, goodness
// 0.15) under the left half of the straight step: with max_driven_step_m 0.20 (80 %) the
// straight arc, and every step that sweeps it, is allowed but marked near the limit and
// named, and the vote takes one that sweeps no cell that high; with 0 (the old rule) the
// straight arc is not marked. A rock read at 50 % (0.125 m) marks nothing, and the 85 % rock
// further on, in the look-ahead only, leaves straight unmarked (planned past, not driven
// over this step).
TEST(ArcVoting, ACellNearTheStepLimitInTheStepIsNotDrivenOver) {
  auto rock = [](double x, double y, float step) {
    Grid g = Open();
    g.Paint(x, y, 0.15, CellClass::kCaution, 1.0f - step / 0.25f, step);
    return g;
  };
  auto straight_of = [](const Choice& c) {
    for (const auto& k : c.candidates)
      if (k.kind == Candidate::Kind::kArc && k.curvature_per_m == 0.0) return k;
    ADD_FAILURE() << "no straight arc";
    return Candidate{};
  };
  VoteOptions o;
  o.max_driven_step_m = 0.20;
  const Grid near_limit = rock(1.1, -0.5, 0.2125f);
  const Choice c = VoteArcs(near_limit, {0, 0, 0}, 5.0, 0.0, o);
  const Candidate straight = straight_of(c);
  EXPECT_FALSE(straight.vetoed);
  EXPECT_TRUE(straight.near_limit);
  EXPECT_NE(straight.near_limit_why.find("step 0.21 m at 1."), std::string::npos) << straight.near_limit_why;
  EXPECT_NE(straight.near_limit_why.find("over the 0.20 m a step drives over"), std::string::npos)
      << straight.near_limit_why;
  ASSERT_TRUE(c.found);
  EXPECT_FALSE(c.best.near_limit);
  EXPECT_FALSE(c.best.kind == Candidate::Kind::kArc && c.best.curvature_per_m == 0.0);
  EXPECT_LT(c.best.step_sweep.max_step_m, 0.20);
  // The old rule: nothing marked, and the best step may cross the rock.
  VoteOptions off = o;
  off.max_driven_step_m = 0.0;
  EXPECT_FALSE(straight_of(VoteArcs(near_limit, {0, 0, 0}, 5.0, 0.0, off)).near_limit);
  // 50 % of the limit: driven over.
  const Choice half = VoteArcs(rock(1.1, -0.5, 0.125f), {0, 0, 0}, 5.0, 0.0, o);
  EXPECT_FALSE(straight_of(half).near_limit) << straight_of(half).near_limit_why;
  // In the look-ahead only: unmarked now, and its goodness counts the rock.
  const Choice later = VoteArcs(rock(2.4, -0.5, 0.2125f), {0, 0, 0}, 5.0, 0.0, o);
  EXPECT_FALSE(straight_of(later).near_limit) << straight_of(later).near_limit_why;
  EXPECT_LT(straight_of(later).goodness, 0.2);
  // Bad values throw.
  VoteOptions bad;
  bad.max_driven_step_m = -0.1;
  EXPECT_THROW(VoteArcs(Open(), {0, 0, 0}, 1, 0, bad), std::invalid_argument);
}

// Ground near the step limit all round (every cell 0.2125 m, caution): no step avoids it,
// and the rover is not boxed in: the vote still takes the best of them, marked (refusing
// such steps outright stopped 5 navbench runs of 6 at k = 0.20 among 0.2 to 0.25 m rocks).
TEST(ArcVoting, GroundNearTheStepLimitAllRoundIsStillDriven) {
  const Grid g = Grid::Filled(-6.0, -6.0, 0.2, 60, 60, CellClass::kCaution, 0.15f);
  Grid near = g;
  near.step_m.assign(near.step_m.size(), 0.2125f);
  VoteOptions o;
  o.max_driven_step_m = 0.20;
  const Choice c = VoteArcs(near, {0, 0, 0}, 5.0, 0.0, o);
  ASSERT_TRUE(c.found) << c.detail;
  EXPECT_TRUE(c.best.near_limit);
  EXPECT_FALSE(c.best.vetoed);
}

TEST(ArcVoting, WallWithAGapToTheLeftSteersLeft) {
  Grid g = Open();
  // Wall across x = 2.5 from y = -0.2 to +5; the gap is west of it (the look-ahead of an
  // arc toward it runs clear, straight ahead and right do not).
  Wall(&g, 2.5, -0.2, 5.0);
  const Choice c = VoteArcs(g, {0, 0, 0}, 5.0, 0.0, VoteOptions{});
  ASSERT_TRUE(c.found);
  const double heading_change = c.best.kind == Candidate::Kind::kTurn ? c.best.turn_rad
                                                                      : c.best.curvature_per_m * c.best.distance_m;
  EXPECT_LT(heading_change, -2 * kDeg) << ToString(c.best.kind) << " k " << c.best.curvature_per_m;
  // The mirror image steers right.
  Grid m = Open();
  Wall(&m, 2.5, -5.0, 0.2);
  const Choice r = VoteArcs(m, {0, 0, 0}, 5.0, 0.0, VoteOptions{});
  ASSERT_TRUE(r.found);
  const double right = r.best.kind == Candidate::Kind::kTurn ? r.best.turn_rad : r.best.curvature_per_m * r.best.distance_m;
  EXPECT_GT(right, 2 * kDeg);
}

TEST(ArcVoting, BoxedInBacksUpOrStopsWithTheHazard) {
  Grid g = Open();
  // Unsafe all round except the rover's own footprint and a lane behind it.
  for (int i = 0; i < g.rows; ++i)
    for (int j = 0; j < g.cols; ++j) {
      const double x = g.CellCentreX(i), y = g.CellCentreY(j);
      const bool under = std::abs(x) < 0.9 && std::abs(y) < 0.8;
      const bool lane = x < 0 && x > -2.0 && std::abs(y) < 0.8;
      if (!under && !lane) {
        const std::size_t k = static_cast<std::size_t>(i) * g.cols + j;
        g.state[k] = CellClass::kUnsafe;
        g.goodness[k] = 0.0f;
        g.step_m[k] = 0.5f;
      }
    }
  const Choice c = VoteArcs(g, {0, 0, 0}, 5.0, 0.0, VoteOptions{});
  ASSERT_TRUE(c.found);
  EXPECT_EQ(c.best.kind, Candidate::Kind::kBackup);
  EXPECT_LT(c.best.distance_m, 0.0);
  VoteOptions no_backup;
  no_backup.backup_m = 0.0;
  const Choice s = VoteArcs(g, {0, 0, 0}, 5.0, 0.0, no_backup);
  EXPECT_FALSE(s.found);
  EXPECT_NE(s.detail.find("step 0.50 m at"), std::string::npos) << s.detail;
  // The lane behind never seen (unknown, wide enough to hide a rock): no backing into it,
  // though it lies within the blind ring that excuses unknown ground elsewhere.
  for (int i = 0; i < g.rows; ++i)
    for (int j = 0; j < g.cols; ++j) {
      const double x = g.CellCentreX(i), y = g.CellCentreY(j);
      if (x < -0.9 && x > -2.0 && std::abs(y) < 0.8) g.state[static_cast<std::size_t>(i) * g.cols + j] = CellClass::kUnknown;
    }
  VoteOptions hidden;
  hidden.unknown.hidden_patch_m = 0.6;
  ASSERT_GT(hidden.blind_margin_m, 0.3);  // the 0.3 m back-up lies within the ring
  const Choice blind = VoteArcs(g, {0, 0, 0}, 5.0, 0.0, hidden);
  EXPECT_FALSE(blind.found);
  bool judged = false;
  for (const Candidate& b : blind.candidates)
    if (b.kind == Candidate::Kind::kBackup) {
      judged = true;
      EXPECT_TRUE(b.vetoed);
      EXPECT_NE(b.why.find("could hide a rock"), std::string::npos) << b.why;
    }
  EXPECT_TRUE(judged);
}

// The cameras have seen the ground ahead (a band 1.2 m either side of the rover's line) but
// not beyond it to the right, where the goal lies (53 deg right). An arc turning toward the
// goal meets a few unseen cells at the far end of its look-ahead: it is worth nearly what
// seen ground is (the share of its cells unknown draws it toward unknown_goodness), not
// as little as a look-ahead wholly unseen, and the rover turns toward the goal. As the worst
// of the two, every arc to the right was worth 0.5 and the straight arc on the seen band won.
TEST(ArcVoting, AFewUnseenCellsAtTheLookAheadsEndCostByTheirShare) {
  Grid g = Open();
  for (int i = 0; i < g.rows; ++i)
    for (int j = 0; j < g.cols; ++j)
      if (g.CellCentreY(j) > 1.2 && g.CellCentreX(i) > -1.0) {
        g.state[static_cast<std::size_t>(i * g.cols + j)] = CellClass::kUnknown;
        g.goodness[static_cast<std::size_t>(i * g.cols + j)] = 0.0f;
      }
  VoteOptions o;
  o.blind_margin_m = 0.0;
  const Choice c = VoteArcs(g, {0, 0, 0}, 3.0, 4.0, o);
  ASSERT_TRUE(c.found);
  const Candidate* gentle = nullptr;  // the gentlest arc to the right
  for (const Candidate& k : c.candidates)
    if (k.kind == Candidate::Kind::kArc && k.curvature_per_m > 0.0 && (!gentle || k.curvature_per_m < gentle->curvature_per_m))
      gentle = &k;
  ASSERT_NE(gentle, nullptr);
  ASSERT_FALSE(gentle->vetoed) << gentle->why;
  EXPECT_GT(gentle->goodness, 0.8) << "a few unseen cells at its end, the rest seen at 0.9";
  EXPECT_LT(gentle->goodness, 0.9);
  // A turn toward the goal, then 3 m straight into the unseen ground: nearer 0.5.
  for (const Candidate& k : c.candidates) {
    if (k.kind == Candidate::Kind::kTurn && std::abs(k.planned_turn_rad - std::atan2(4.0, 3.0)) < 1e-6) {
      EXPECT_LT(k.goodness, gentle->goodness);
    }
  }
  const double heading_change = c.best.kind == Candidate::Kind::kTurn ? c.best.turn_rad
                                                                      : c.best.curvature_per_m * c.best.distance_m;
  EXPECT_GT(heading_change, 2 * kDeg) << ToString(c.best.kind) << " k " << c.best.curvature_per_m;
}

TEST(ArcVoting, UnknownAheadAllowsOnlyTheBlindRing) {
  // Unknown everywhere: a full step straight ahead is vetoed; whatever is allowed stays
  // inside the ring the mast cameras cannot see from where the rover stands.
  const Grid u = Grid::Filled(-6.0, -6.0, 0.2, 60, 60, CellClass::kUnknown, 0.0f);
  const Choice c = VoteArcs(u, {0, 0, 0}, 5.0, 0.0, VoteOptions{});
  int vetoed = 0;
  for (const auto& k : c.candidates) {
    if (k.kind == Candidate::Kind::kArc && k.curvature_per_m == 0.0) {
      EXPECT_TRUE(k.vetoed);
      EXPECT_NE(k.why.find("% of the cells crossed are unknown"), std::string::npos) << k.why;
    }
    if (k.vetoed) {
      ++vetoed;
    } else {
      EXPECT_LE(k.step_sweep.UnknownFraction(), 0.2);
    }
  }
  EXPECT_GT(vetoed, 10);
}

// Unknown ground wide enough to hide a rock, straight ahead: with hidden_patch_m the
// straight arc is vetoed by it, though its share of the step's cells is under the limit
// for scattered unknown cells; a step round the patch is chosen. Under the fraction limit
// the straight arc wins.
TEST(ArcVoting, UnknownGroundWideEnoughToHideARockIsSteeredRound) {
  Grid g = Open();
  g.Paint(1.7, 0.0, 0.4, CellClass::kUnknown, 0.0f, 0.0f);  // 0.8 m across, the ring its near edge
  VoteOptions o;
  o.unknown.max_fraction = 0.5;
  const Choice fraction_only = VoteArcs(g, {0, 0, 0}, 5.0, 0.0, o);
  ASSERT_TRUE(fraction_only.found);
  const auto straight = [](const Choice& c) -> const Candidate* {
    for (const auto& k : c.candidates)
      if (k.kind == Candidate::Kind::kArc && k.curvature_per_m == 0.0) return &k;
    return nullptr;
  };
  ASSERT_NE(straight(fraction_only), nullptr);
  EXPECT_FALSE(straight(fraction_only)->vetoed) << straight(fraction_only)->why;

  o.unknown = {0.05, 0.6, 0.5};
  const Choice c = VoteArcs(g, {0, 0, 0}, 5.0, 0.0, o);
  ASSERT_NE(straight(c), nullptr);
  EXPECT_TRUE(straight(c)->vetoed);
  EXPECT_NE(straight(c)->why.find("unknown ground 0.60 m across at "), std::string::npos) << straight(c)->why;
  ASSERT_TRUE(c.found);
  EXPECT_EQ(c.best.step_sweep.hidden, 0);
  EXPECT_FALSE(c.best.kind == Candidate::Kind::kArc && c.best.curvature_per_m == 0.0);
}

// A rock just off the rover's nose, a little to its left, and the goal ahead and 45 deg to
// the right: every step ahead crosses the rock, and so does a turn left. The way on is a
// turn right of more than one step's 18 deg; it is judged whole and its first part driven.
Grid NoseAtARock() {
  Grid g = Open();
  g.Paint(1.6, -0.5, 0.35, CellClass::kUnsafe, 0.0f, 0.35f);
  return g;
}

TEST(ArcVoting, AWayOnMoreThanOneTurnRoundIsSeenAndStarted) {
  const Choice c = VoteArcs(NoseAtARock(), {0, 0, 0}, 3.0, 3.0, VoteOptions{});
  ASSERT_TRUE(c.found);
  ASSERT_EQ(c.best.kind, Candidate::Kind::kTurn) << ToString(c.best.kind) << " k " << c.best.curvature_per_m;
  EXPECT_NEAR(c.best.turn_rad, 18.0 * kDeg, 1e-9);       // one step's turn is driven ...
  EXPECT_GT(c.best.planned_turn_rad, 30.0 * kDeg);       // ... of a longer one judged
  EXPECT_GE(c.best.clear_m, 0.6);
  // Judged one step round only, the same turn would lead nowhere.
  VoteOptions one;
  one.max_point_turn_rad = one.max_turn_rad;
  const Choice d = VoteArcs(NoseAtARock(), {0, 0, 0}, 3.0, 3.0, one);
  for (const auto& k : d.candidates)
    if (k.kind == Candidate::Kind::kTurn && k.turn_rad > 0) {
      EXPECT_LT(k.clear_m, 0.6);
    }
}

TEST(ArcVoting, ATurnThatWouldUndoTheLastIsVetoed) {
  VoteOptions o;
  o.previous_turn_rad = 18.0 * kDeg;
  const Choice c = VoteArcs(NoseAtARock(), {0, 0, 0}, 3.0, -3.0, o);
  int undo = 0;
  for (const auto& k : c.candidates)
    if (k.kind == Candidate::Kind::kTurn && k.turn_rad < 0) {
      EXPECT_TRUE(k.vetoed);
      EXPECT_EQ(k.why, "it would undo the last turn");
      ++undo;
    }
  EXPECT_GE(undo, 5);
  ASSERT_TRUE(c.found);
  EXPECT_FALSE(c.best.kind == Candidate::Kind::kTurn && c.best.turn_rad < 0);
}

// Boxed in, as navbench seed 11 k0.20_r06 was near its start: rock across the nose (every
// arc, and every turn beyond one step's 18 deg, swings into it), ground never seen ahead on
// the right (a turn right's front corner sweeps it) and behind (the backup).
Grid BoxedNearTheStart() {
  Grid g = Open();
  Wall(&g, 1.3, -3.0, 3.0);
  MarkUnknown(&g, 0.2, 1.0, 0.8, 2.0);     // ahead on the right, beside the body
  MarkUnknown(&g, -2.0, -1.0, -2.0, 2.0);  // behind
  return g;
}

// The executor's strict rule for unseen ground: no blind ring excused.
VoteOptions Strict() {
  VoteOptions o;
  o.blind_margin_m = 0.0;
  o.unknown.hidden_patch_m = 0.6;
  o.unknown.hidden_at_any_share = true;
  return o;
}

// The last step a turn right: the turn left, the one step whose sweep is safe and seen,
// would undo it. It is taken rather than no step (without that: no step, an abort).
TEST(ArcVoting, BoxedInTheTurnBackIsTakenRatherThanNoStep) {
  VoteOptions o = Strict();
  o.previous_turn_rad = 18.0 * kDeg;
  const Choice c = VoteArcs(BoxedNearTheStart(), {0, 0, 0}, 5.0, 0.0, o);
  ASSERT_TRUE(c.found) << c.detail;
  EXPECT_EQ(c.best.kind, Candidate::Kind::kTurn);
  EXPECT_NEAR(c.best.turn_rad, -18.0 * kDeg, 1e-9);
  EXPECT_TRUE(c.best.undoes_last_turn);
  EXPECT_EQ(c.best.why, kUndoWhy);
  // Every other candidate is vetoed for the ground it crosses.
  for (const auto& k : c.candidates) {
    if (!k.undoes_last_turn) {
      EXPECT_TRUE(k.vetoed) << ToString(k.kind) << " " << k.curvature_per_m << " " << k.turn_rad;
    }
  }
}

// With the left front unseen as well, nothing is allowed, and the detail says why of every
// kind of step, not only the worst rock.
TEST(ArcVoting, WhenNothingIsAllowedTheDetailCountsEveryKindOfVeto) {
  Grid g = BoxedNearTheStart();
  MarkUnknown(&g, 0.2, 1.0, -2.0, -0.8);
  VoteOptions o = Strict();
  o.previous_turn_rad = 18.0 * kDeg;
  const Choice c = VoteArcs(g, {0, 0, 0}, 5.0, 0.0, o);
  ASSERT_FALSE(c.found) << ToString(c.best.kind) << " " << c.best.turn_rad;
  EXPECT_EQ(c.detail.rfind("no safe step among 32 candidates: step 0.40 m at ", 0), 0u) << c.detail;
  EXPECT_NE(c.detail.find("(21 arcs: 21 over unsafe ground; 10 turns: 8 over unsafe ground, 2 over unknown ground; "
                          "backup: unknown ground 0.60 m across at "),
            std::string::npos)
      << c.detail;
  EXPECT_EQ(VetoSummary({}), "");
}

TEST(ArcVoting, ARoverWhoseEveryWayOnIsBlockedBacksAwayRatherThanTurning) {
  // A wall of rock right across the nose: no arc is allowed and every turn in place
  // (allowed: the corners clear it) faces rock within one step. Backing up wins.
  Grid g = Open();
  for (double y = -3.0; y <= 3.0; y += 0.2) g.Paint(1.05, y, 0.15, CellClass::kUnsafe, 0.0f, 0.4f);
  for (double x = -3.0; x <= 1.0; x += 0.2) {
    g.Paint(x, -1.5, 0.15, CellClass::kUnsafe, 0.0f, 0.4f);
    g.Paint(x, 1.5, 0.15, CellClass::kUnsafe, 0.0f, 0.4f);
  }
  VoteOptions o;
  o.max_point_turn_rad = o.max_turn_rad;
  const Choice c = VoteArcs(g, {0, 0, 0}, 5.0, 0.0, o);
  ASSERT_TRUE(c.found);
  bool some_turn_allowed = false;
  for (const auto& k : c.candidates) some_turn_allowed |= k.kind == Candidate::Kind::kTurn && !k.vetoed;
  EXPECT_TRUE(some_turn_allowed);
  EXPECT_EQ(c.best.kind, Candidate::Kind::kBackup) << ToString(c.best.kind) << " " << c.best.turn_rad;
}

// The rover has just driven a sharp arc forward and meets rock all round: every step ahead
// and every turn is refused, and backing up straight would swing the body's rear over
// ground beside the way it came (rock here; on a rover, as often ground the cameras facing
// ahead never saw). Backing up along the arc just driven retraces the ground it drove.
// Rock (0.4 m) everywhere but the cells a 1.6 x 1.4 m body covered (within 0.1 m) along
// `came`.
Grid RockBeyondTheGroundDriven(const std::vector<Pose2>& came) {
  Grid g = Open();
  for (int i = 0; i < g.rows; ++i)
    for (int j = 0; j < g.cols; ++j) {
      const double x = g.CellCentreX(i), y = g.CellCentreY(j);
      bool driven = false;
      for (const Pose2& p : came) {
        const double dx = x - p.x, dy = y - p.y;
        const double along = dx * std::cos(p.yaw) + dy * std::sin(p.yaw);
        const double across = -dx * std::sin(p.yaw) + dy * std::cos(p.yaw);
        driven = driven || (std::abs(along) <= 0.8 + 0.1 && std::abs(across) <= 0.7 + 0.1);
      }
      if (!driven) {
        const std::size_t c = static_cast<std::size_t>(i) * g.cols + j;
        g.state[c] = CellClass::kUnsafe;
        g.goodness[c] = 0.0f;
        g.step_m[c] = 0.4f;
      }
    }
  return g;
}

void ExpectBacksUpAlong(const Choice& c, double distance_m, double curvature_per_m) {
  ASSERT_TRUE(c.found) << c.detail;
  EXPECT_EQ(c.best.kind, Candidate::Kind::kBackup);
  EXPECT_NEAR(c.best.distance_m, -distance_m, 1e-9);
  EXPECT_NEAR(c.best.curvature_per_m, curvature_per_m, 1e-9);
}

TEST(ArcVoting, BoxedInAfterAnArcBacksUpAlongTheArcItDrove) {
  const double k = 1.0, arc = 0.6;
  const Pose2 here{0, 0, 0};
  const auto came = SamplePath(here, 0.0, -arc, k);  // back along the arc: where it was
  ASSERT_GT(std::abs(came.back().yaw), 20.0 * kDeg);
  const Grid g = RockBeyondTheGroundDriven(came);
  VoteOptions o;
  const Choice stuck = VoteArcs(g, here, 5.0, 0.0, o);
  EXPECT_FALSE(stuck.found) << ToString(stuck.best.kind) << " " << stuck.best.distance_m;
  o.previous_arc_m = arc;
  o.previous_arc_curvature_per_m = k;
  const Choice c = VoteArcs(g, here, 5.0, 0.0, o);
  ExpectBacksUpAlong(c, o.backup_m, k);
  // The straight backup was judged first, and refused.
  int straight = 0;
  for (const Candidate& b : c.candidates)
    if (b.kind == Candidate::Kind::kBackup && b.curvature_per_m == 0.0) {
      ++straight;
      EXPECT_TRUE(b.vetoed);
    }
  EXPECT_EQ(straight, 1);
  // A previous arc shorter than backup_m is retraced no further than it ran.
  o.previous_arc_m = 0.2;
  const Choice shorter = VoteArcs(g, here, 5.0, 0.0, o);
  ASSERT_TRUE(shorter.found);
  EXPECT_NEAR(shorter.best.distance_m, -0.2, 1e-9);
  o.previous_arc_m = -0.1;
  EXPECT_THROW(VoteArcs(g, here, 5.0, 0.0, o), std::invalid_argument);
  // With the plan's way behind, backing up is voted on with the arcs and turns; the arc is
  // retraced then too (navbench seed 7 k0.30_r01 stopped "no safe step" so, its straight
  // backup's corner over unseen ground and the arc it drove never judged).
  o.previous_arc_m = arc;
  o.way_heading_rad = M_PI;
  ExpectBacksUpAlong(VoteArcs(g, here, 5.0, 0.0, o), o.backup_m, k);
}

// The vote's footprint carries a margin beyond the body; backing up along the arc just
// driven sweeps only the ground the body covered, and is judged on the body alone: the
// margin's ring beside the arc, rated unsafe since, does not box the rover in.
TEST(ArcVoting, BoxedInItRetracesTheArcOnTheBodyAloneNotTheMarginsRing) {
  const double k = 1.0, arc = 0.6, margin = 0.1;
  const Pose2 here{0, 0, 0};
  const Grid g = RockBeyondTheGroundDriven(SamplePath(here, 0.0, -arc, k));
  VoteOptions o;
  o.footprint.length_m += 2.0 * margin;
  o.footprint.width_m += 2.0 * margin;
  o.previous_arc_m = arc;
  o.previous_arc_curvature_per_m = k;
  // Judged with the margin, every backup crosses the ring.
  const Choice with_margin = VoteArcs(g, here, 5.0, 0.0, o);
  EXPECT_FALSE(with_margin.found) << ToString(with_margin.best.kind) << " " << with_margin.best.distance_m;
  o.footprint_margin_m = margin;
  const Choice c = VoteArcs(g, here, 5.0, 0.0, o);
  ExpectBacksUpAlong(c, o.backup_m, k);
  // The straight backup keeps the margin: it leaves the ground driven.
  for (const Candidate& b : c.candidates) {
    if (b.kind == Candidate::Kind::kBackup && b.curvature_per_m == 0.0) {
      EXPECT_TRUE(b.vetoed);
    }
  }
  o.footprint_margin_m = 0.8;  // as wide as the body: no body left
  EXPECT_THROW(VoteArcs(g, here, 5.0, 0.0, o), std::invalid_argument);
}

// With the rover's suspension, ACE's clearance bounds from the grid's heights, not the
// cells' ratings, decide what is safe (common/clearance).
Grid OpenWithHeights() {
  Grid g = Open();
  g.SetHeights(0.0f, 0.01f);
  return g;
}

VoteOptions WithSuspension() {
  VoteOptions o;
  o.suspension = clearance::Suspension{};
  return o;
}

const Candidate* Straight(const Choice& c) {
  for (const auto& k : c.candidates)
    if (k.kind == Candidate::Kind::kArc && k.curvature_per_m == 0.0) return &k;
  return nullptr;
}

TEST(ArcVotingClearance, ALowRockBetweenTheWheelsIsDrivenOver) {
  // A rock 0.12 m tall and 0.3 m across on the line, between the wheel tracks: the belly
  // (0.30 m up) clears it by more than the 0.10 m asked. The cells rate it unsafe.
  Grid g = OpenWithHeights();
  g.Paint(1.5, 0.0, 0.15, CellClass::kUnsafe, 0.0f, 0.12f);
  const Choice cells = VoteArcs(g, {0, 0, 0}, 5.0, 0.0, VoteOptions{});
  ASSERT_NE(Straight(cells), nullptr);
  EXPECT_LT(Straight(cells)->clear_m, 3.0);  // the cells stop the look-ahead at the rock
  VoteOptions o = WithSuspension();
  EXPECT_LT(Straight(VoteArcs(g, {0, 0, 0}, 5.0, 0.0, o))->clear_m, 3.0);  // the cells still stop it
  o.cells_too = false;
  const Choice ace = VoteArcs(g, {0, 0, 0}, 5.0, 0.0, o);
  ASSERT_NE(Straight(ace), nullptr);
  EXPECT_FALSE(Straight(ace)->vetoed) << Straight(ace)->why;
  EXPECT_NEAR(Straight(ace)->clear_m, 3.0, 1e-6);
  // Its goodness is the margin left, at most (0.30 - 0.12 - 0.10) / (0.30 - 0.10) of the
  // clearance (less the heights' uncertainty). Open ground leaves more.
  EXPECT_GT(Straight(ace)->goodness, 0.0);
  EXPECT_LT(Straight(ace)->goodness, (0.30 - 0.12 - 0.10) / 0.20);
  const Choice open = VoteArcs(OpenWithHeights(), {0, 0, 0}, 5.0, 0.0, o);
  EXPECT_GT(Straight(open)->goodness, Straight(ace)->goodness + 0.3);
}

TEST(ArcVotingClearance, ATallRockBetweenTheWheelsIsSteeredRound) {
  Grid g = OpenWithHeights();
  g.Paint(1.2, 0.0, 0.15, CellClass::kSafe, 0.9f, 0.35f);  // taller than the belly is high
  const Choice c = VoteArcs(g, {0, 0, 0}, 5.0, 0.0, WithSuspension());
  ASSERT_NE(Straight(c), nullptr);
  EXPECT_TRUE(Straight(c)->vetoed);
  EXPECT_NE(Straight(c)->why.find("belly clearance"), std::string::npos) << Straight(c)->why;
  ASSERT_TRUE(c.found);
  EXPECT_FALSE(c.best.kind == Candidate::Kind::kArc && c.best.curvature_per_m == 0.0);
}

TEST(ArcVotingClearance, UnknownGroundAheadShortensWhatIsClear) {
  // Ground beyond the blind ring the map has no height for, 0.8 m across, on the line.
  Grid g = OpenWithHeights();
  g.Paint(1.7, 0.0, 0.4, CellClass::kUnknown, 0.0f, 0.0f);
  VoteOptions o = WithSuspension();
  o.cells_too = false;
  o.unknown.max_fraction = 0.5;
  const Choice c = VoteArcs(g, {0, 0, 0}, 5.0, 0.0, o);
  ASSERT_NE(Straight(c), nullptr);
  // A rock unknown_rise_m tall could stand there: the look-ahead is clear only until the
  // belly reaches it.
  EXPECT_LT(Straight(c)->clear_m, 1.0);
  // A rover that assumed unknown ground level would see the whole look-ahead clear.
  o.suspension->unknown_rise_m = 0.0;
  const Choice level = VoteArcs(g, {0, 0, 0}, 5.0, 0.0, o);
  EXPECT_NEAR(Straight(level)->clear_m, 3.0, 1e-6);
}

TEST(ArcVotingClearance, NothingAllowedNamesTheClearanceItBreaks) {
  // Boxed in by rock taller than the underside, here the whole 1.6 x 1.4 m footprint: every
  // arc and every turn in place brings rock under it.
  Grid g = OpenWithHeights();
  for (int i = 0; i < g.rows; ++i)
    for (int j = 0; j < g.cols; ++j) {
      const double x = g.CellCentreX(i), y = g.CellCentreY(j);
      if (std::abs(x) < 0.9 && std::abs(y) < 0.8) continue;
      g.elevation_m[static_cast<std::size_t>(i) * g.cols + j] = 0.5f;
    }
  VoteOptions o = WithSuspension();
  o.cells_too = false;
  o.suspension->belly_min_x_m = -0.8;
  o.suspension->belly_max_x_m = 0.8;
  o.suspension->belly_width_m = 1.4;
  o.backup_m = 0.0;
  const Choice c = VoteArcs(g, {0, 0, 0}, 5.0, 0.0, o);
  EXPECT_FALSE(c.found);
  EXPECT_NE(c.detail.find("clearance at "), std::string::npos) << c.detail;
}

TEST(ArcVotingClearance, AGridWithoutHeightsCannotBeJudged) {
  EXPECT_THROW(VoteArcs(Open(), {0, 0, 0}, 5.0, 0.0, WithSuspension()), std::invalid_argument);
}

// Ground beside the rover the cameras never saw (the mast cameras look ahead; a rock
// there once hid beside the view and was struck on a turn), the goal to the left. With
// the blind ring excused (blind_margin_m 0.5) the turns left sweep that ground unjudged;
// with none (the executor's default), every turn left is vetoed as ground that could hide
// a rock. Ground the first part of a turn sweeps, once known (seen, or driven over:
// Grid::MarkKnown), lets the turn start: the rest of it is seen from there before it is
// driven, so a turn of 90 deg is judged on its first step's ground.
TEST(ArcVoting, ATurnIntoGroundNeverSeenIsVetoedUnlessTheRingIsExcused) {
  Grid g = Open();
  for (int i = 0; i < g.rows; ++i)
    for (int j = 0; j < g.cols; ++j)
      if (g.CellCentreY(j) < -0.8 && std::abs(g.CellCentreX(i)) < 2.5) {
        const std::size_t k = static_cast<std::size_t>(i) * g.cols + j;
        g.state[k] = CellClass::kUnknown;
        g.goodness[k] = 0.0f;
      }
  const Pose2 here{0.0, 0.0, 0.0};
  VoteOptions excused;
  excused.unknown = {0.2, 0.6, 0.5};  // hazard_monitor's
  excused.blind_margin_m = 0.5;
  VoteOptions strict = excused;
  strict.blind_margin_m = 0.0;
  auto left_turns = [](const Choice& c) {
    std::vector<const Candidate*> out;
    for (const auto& k : c.candidates)
      if (k.kind == Candidate::Kind::kTurn && k.turn_rad < 0.0) out.push_back(&k);
    return out;
  };
  const Choice loose = VoteArcs(g, here, 0.0, -4.0, excused);
  int allowed = 0;
  for (const Candidate* k : left_turns(loose)) allowed += !k->vetoed;
  EXPECT_GT(allowed, 0);  // the hole: unseen ground swept by the body's corners

  const Choice c = VoteArcs(g, here, 0.0, -4.0, strict);
  ASSERT_GE(left_turns(c).size(), 5u);
  for (const Candidate* k : left_turns(c)) {
    EXPECT_TRUE(k->vetoed) << k->planned_turn_rad / kDeg;
    EXPECT_NE(k->why.find("could hide a rock"), std::string::npos) << k->why;
  }
  EXPECT_FALSE(c.found && c.best.kind == Candidate::Kind::kTurn && c.best.turn_rad < 0.0);

  // The ground the first 18 deg of a turn left sweeps becomes known (the rover drove over
  // it, or saw it from further back): the turns left may start, the rest still unseen.
  Grid first = g;
  for (const Pose2& p : SamplePath(here, -strict.max_turn_rad, 0.0, 0.0))
    first.MarkKnown(strict.footprint, p, 0.5 * first.cell_m);
  EXPECT_EQ(first.MarkKnown(strict.footprint, here, 0.5 * first.cell_m), 0);  // already known
  const Choice d = VoteArcs(first, here, 0.0, -4.0, strict);
  const Candidate* quarter = nullptr;
  for (const Candidate* k : left_turns(d))
    if (std::abs(k->planned_turn_rad + 90.0 * kDeg) < 1e-9) quarter = k;
  ASSERT_NE(quarter, nullptr);
  EXPECT_FALSE(quarter->vetoed) << quarter->why;
  EXPECT_NEAR(quarter->turn_rad, -strict.max_turn_rad, 1e-12);
  EXPECT_EQ(quarter->step_sweep.unknown, 0);  // judged on what its first step covers
  ASSERT_TRUE(d.found);
  EXPECT_EQ(d.best.kind, Candidate::Kind::kTurn);
  EXPECT_LT(d.best.turn_rad, 0.0);
}

// An arc whose body corner sweeps a few cells of unseen ground beside the view: under the
// 20 % share of unknown cells a step may cross, but the ground there is wide enough to hide
// a rock (a 0.30 m rock once stood beside the view and was struck so, on an arc). With
// hidden_at_any_share the arc is refused whatever the share; without, it is allowed.
TEST(ArcVoting, ACornerSweptIntoGroundThatCouldHideARockIsRefusedAtAnyShare) {
  Grid g = Open();
  for (int i = 0; i < g.rows; ++i)
    for (int j = 0; j < g.cols; ++j)
      if (g.CellCentreY(j) > 0.8 && g.CellCentreX(i) > 0.5 && g.CellCentreX(i) < 3.0) {
        const std::size_t k = static_cast<std::size_t>(i) * g.cols + j;
        g.state[k] = CellClass::kUnknown;
        g.goodness[k] = 0.0f;
      }
  VoteOptions o;
  o.blind_margin_m = 0.0;
  o.unknown = {0.2, 0.6, 0.5};
  const auto right_arc = [](const Choice& c) -> const Candidate* {
    for (const auto& k : c.candidates)
      if (k.kind == Candidate::Kind::kArc && std::abs(k.curvature_per_m - 0.3) < 1e-9) return &k;
    return nullptr;
  };
  const Choice share = VoteArcs(g, {0, 0, 0}, 5.0, 2.0, o);
  const Candidate* a = right_arc(share);
  ASSERT_NE(a, nullptr);
  ASSERT_GT(a->step_sweep.unknown, 0);
  ASSERT_GT(a->step_sweep.hidden, 0);
  EXPECT_LE(a->step_sweep.UnknownFraction(), 0.2);
  EXPECT_FALSE(a->vetoed) << a->why;  // the share alone lets it through

  o.unknown.hidden_at_any_share = true;
  const Choice strict = VoteArcs(g, {0, 0, 0}, 5.0, 2.0, o);
  const Candidate* b = right_arc(strict);
  ASSERT_NE(b, nullptr);
  EXPECT_TRUE(b->vetoed);
  EXPECT_NE(b->why.find("could hide a rock"), std::string::npos) << b->why;
  ASSERT_TRUE(strict.found);  // straight ahead is seen ground
  EXPECT_EQ(strict.best.step_sweep.hidden, 0);
}

TEST(ArcVoting, BadInputThrowsOneLine) {
  Grid g = Open();
  g.goodness.pop_back();
  EXPECT_THROW(VoteArcs(g, {0, 0, 0}, 1, 0, VoteOptions{}), std::invalid_argument);
  VoteOptions o;
  o.lookahead_m = -1;
  EXPECT_THROW(VoteArcs(Open(), {0, 0, 0}, 1, 0, o), std::invalid_argument);
}

}  // namespace
}  // namespace rover::avoidance
