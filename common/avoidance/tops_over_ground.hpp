// Rocks whose cells' tops stand over the ground round them: what the vote reads from the
// map's heights when the map's own rating reads a rock low. No LCM.
#pragma once

#include "avoidance/grid.hpp"

namespace rover::avoidance {

// Every safe or caution cell whose top (Grid::elevation_m: the map's cell top, its points'
// mean plus one standard deviation) stands min_rise_m or more over the ground round it
// becomes unsafe (goodness 0; its step_m raised to that rise when the rise is higher).
//
// The ground round a cell is a plane fitted (least squares, Eigen) to the heights of the
// known cells within radius_m of it, refitted without the cells more than a third of
// min_rise_m above it until the set no longer changes (at most 5 fits), so that it lies on
// the ground a rock stands on and not on the rock or its lower flanks, and so that a uniform
// slope rises nothing. (With half of it, the flanks of navbench seed 41's 0.31 m rock held the
// plane 0.04 m up, and its tops, read 0.27 m, rose only 0.23 m.) Fewer than 6 known cells round it: the cell keeps its rating.
//
// Why: the map rates a cell's step from its points' mean height, about a plane its own
// rock raises, and its top rarely enters the step (traversability's cell_plane_sigmas, off:
// counted everywhere, the planner's obstacles grow and dense fields close). navbench seed
// 41, k0.25_r16: a 0.31 m rock's nine cells read steps of 0.20 to 0.25 m (caution; the
// limit 0.25) in every map while their tops stood up to 0.27 m over ground at 0.00 to
// 0.01 m, and the body swept it. Judging the vote's cells by their tops keeps the body's
// sweep off such a rock without changing the plan's obstacles.
//
// Cells more than this share of the rise limit over the plane are left out of the ground.
inline constexpr double kTopGroundBandFraction = 1.0 / 3.0;

// Grids without heights (HasHeights false) change nothing. Returns how many cells changed.
int MarkTopsOverGround(Grid* grid, double radius_m, double min_rise_m);

// The rise of cell k's top over the ground round it as MarkTopsOverGround fits it, or a
// negative value when it has no height or too few known cells round it.
double TopOverGround(const Grid& grid, int k, double radius_m, double band_m);

}  // namespace rover::avoidance
