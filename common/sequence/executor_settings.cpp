// Starting a command: a motion is split into the steps the machine drives one by one (a
// goto is planned step by step as it goes); a setting takes effect at once, and the ones
// that wait for something (images, a new site) enter the phase that waits for it.
#include "sequence/executor.hpp"

#include <algorithm>
#include <cmath>

namespace rover::sequence {

void SequenceExecutor::StartCommand() {
  const Command& c = sequence_.commands[command_index_];
  detail_ = "line " + std::to_string(c.line) + ": " + c.text;
  EmitStatus();
  if (!IsMotion(c)) {
    ApplySetting(c);
    return;
  }
  command_active_ = true;
  is_goto_ = false;
  steps_.clear();
  next_step_ = 0;
  no_progress_count_ = 0;
  lost_step_scale_ = 1.0;
  PlanMotion(c);
  EnterPhase(Phase::kReady);
}

void SequenceExecutor::PlanMotion(const Command& c) {
  if (const auto* d = std::get_if<Drive>(&c.action)) {
    steps_ = SplitArc(d->distance_m, 0.0, step_m_, max_turn_rad_);
  } else if (const auto* a = std::get_if<Arc>(&c.action)) {
    steps_ = SplitArc(a->distance_m, 1.0 / a->radius_m, step_m_, max_turn_rad_);
  } else if (const auto* t = std::get_if<Turn>(&c.action)) {
    steps_ = SplitTurn(t->angle_rad, max_turn_rad_);
  } else if (const auto* h = std::get_if<TurnTo>(&c.action); h && PoseFinite()) {
    const double turn = ShortestTurn(CurrentPlanePose().yaw, h->heading_rad);
    if (std::abs(turn) > 1e-4) steps_ = SplitTurn(turn, max_turn_rad_);
  } else if (const auto* g = std::get_if<Goto>(&c.action)) {
    is_goto_ = true;
    goto_ = *g;
    avoid_history_.clear();
    ahead_declined_ = false;
    blocked_ways_.Reset();
    refused_ways_.Reset();
    last_turn_rad_ = 0.0;
    arcs_to_retrace_.Clear();
    goto_start_utime_ = now_utime_;
    goto_start_pose_.reset();
    if (PoseFinite()) {
      const PlanePose s = CurrentPlanePose();
      goto_start_pose_ = avoidance::Pose2{s.x, s.y, s.yaw};
    }
    goto_start_distance_ = distance_m_;
    const PlanePose p = CurrentPlanePose();
    const double straight = (g->target - Eigen::Vector2d(p.x, p.y)).norm();
    goto_distance_limit_ = g->distance_limit_m ? *g->distance_limit_m
                                               : options_.goto_default_distance_factor * straight +
                                                     options_.goto_default_distance_margin_m;
  }
}

void SequenceExecutor::ApplySetting(const Command& c) {
  if (std::holds_alternative<NewSite>(c.action)) {
    StartNewSite();
    return;
  }
  if (const auto* im = std::get_if<Images>(&c.action)) {
    StartImages(*im);
    return;
  }
  if (!ApplyKeepOut(c)) ApplyStepSetting(c);
  EnterPhase(Phase::kReady);
}

void SequenceExecutor::ApplyStepSetting(const Command& c) {
  if (const auto* v = std::get_if<VoSetting>(&c.action)) {
    vo_enabled_ = v->enabled;
    if (v->step_m) step_m_ = *v->step_m;
    if (v->max_turn_rad) max_turn_rad_ = *v->max_turn_rad;
    if (v->max_failures) {
      vo_max_failures_ = v->max_failures;
      vo_past_max_ = v->past_max.value_or(VoFailureAction::kContinue);
    }
    if (v->wait_s) vo_wait_s_ = *v->wait_s;
    vo_policy_failures_ = 0;
    vo_off_by_failures_ = false;
  } else if (const auto* l = std::get_if<VoLostSetting>(&c.action)) {
    vo_lost_ = *l;
    if (l->slope_rad) blind_slope_rad_ = *l->slope_rad;
    if (l->slip_pct) blind_slip_pct_ = *l->slip_pct;
  } else if (const auto* s = std::get_if<SlipSetting>(&c.action)) {
    slip_ = *s;
    no_progress_count_ = 0;
  } else if (const auto* t = std::get_if<TiltSetting>(&c.action)) {
    tilt_ = *t;
  } else if (const auto* l = std::get_if<LimitSetting>(&c.action)) {
    if (l->time_s) limits_.time_s = l->time_s;
    if (l->distance_m) limits_.distance_m = l->distance_m;
  }
}

bool SequenceExecutor::ApplyKeepOut(const Command& c) {
  const auto drop = [&](const std::string& name) {
    zones_.erase(std::remove_if(zones_.begin(), zones_.end(),
                                [&](const KeepOutZone& z) { return z.name == name; }),
                 zones_.end());
  };
  if (const auto* k = std::get_if<KeepOutAdd>(&c.action)) {
    drop(k->zone.name);
    zones_.push_back(k->zone);
  } else if (const auto* r = std::get_if<KeepOutRemove>(&c.action)) {
    drop(r->name);
  } else if (std::holds_alternative<KeepOutClear>(c.action)) {
    zones_.clear();
  } else {
    return false;
  }
  PublishZones();
  return true;
}

void SequenceExecutor::PublishZones() { Emit(KeepOutZoneSet{now_utime_, zones_}); }

void SequenceExecutor::StartNewSite() {
  wait_site_index_ = (pose_ ? pose_->site_index : 0) + 1;
  Emit(NewSiteRequest{now_utime_, wait_site_index_});
  // Zones were given in the old site frame; they mean nothing in the new one.
  if (!zones_.empty()) {
    zones_.clear();
    PublishZones();
  }
  EnterPhase(Phase::kSite);
}

void SequenceExecutor::StartImages(const Images& images) {
  if (images.purpose == ImagePurpose::kVoBaseline) {
    StartCapture("vo_baseline");
    vo_frame_valid_ = true;
    if (VoActive()) {
      EnterPhase(Phase::kBaseline);
      return;
    }
  } else {
    StartCapture("science");
  }
  science_frame_seen_ = false;
  EnterPhase(Phase::kImages);
}

}  // namespace rover::sequence
