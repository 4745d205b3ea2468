#include "haptic/parameter_mailbox.h"

#include <algorithm>

#include "analysis/model/sensory_model.h"

namespace doorbench::haptic {

DoorModel playable_model(const DoorModel& model) {
  if (!model.has_effect(effects::Kind::kForceOffset)) return model;
  std::vector<EffectSetting> kept;
  for (const EffectSetting& effect : model.effects()) {
    if (effect.kind != effects::Kind::kForceOffset) kept.push_back(effect);
  }
  const int base = model.base_parameter_count();
  const auto values = model.parameter_values();
  const auto bounds = model.parameter_bounds();
  return DoorModel(model.kind(), model.geometry(),
                   std::vector<double>(values.begin(), values.begin() + base),
                   std::vector<Bounds>(bounds.begin(), bounds.begin() + base), std::move(kept));
}

PlaybackParameters::PlaybackParameters(const DoorModel& door_model, const DoorMapping& mapping,
                                       std::string what)
    : model(playable_model(door_model)),
      device_inertia(mapping.inertia_on_device(model.inertia_kg_m2())),
      description(std::move(what)) {
  // The sensory model's snap (negative damping, door-models.md §2) is the one term that puts
  // energy into the door; the physical model's terms and the catalogue's effects are
  // conservative or dissipative for parameters inside their bounds.
  if (model.kind() == ModelKind::kSensory) active_terms.push_back(sensory::kSnap);
}

ParameterMailbox::~ParameterMailbox() {
  // A set still pending was never taken: it is owned by kept_ like every other.
  pending_.store(nullptr);
}

int ParameterMailbox::publish(std::unique_ptr<PlaybackParameters> parameters) {
  if (!parameters) throw std::invalid_argument("ParameterMailbox::publish: no parameter set");
  parameters->id = next_id_++;
  parameters->published_time_s = monotonic_now_s();
  last_published_time_s_ = parameters->published_time_s;
  PlaybackParameters* raw = parameters.get();
  kept_.push_back(std::move(parameters));
  PlaybackParameters* dropped = pending_.exchange(raw, std::memory_order_acq_rel);
  if (dropped) {
    // The tick never saw it: free it now.
    std::erase_if(kept_, [dropped](const std::unique_ptr<PlaybackParameters>& kept) {
      return kept.get() == dropped;
    });
  }
  reclaim();
  return raw->id;
}

std::size_t ParameterMailbox::reclaim() {
  const int in_use = in_use_id_.load(std::memory_order_acquire);
  const PlaybackParameters* pending = pending_.load(std::memory_order_acquire);
  // Older than the set in use, and not the pending one (which is always the newest).
  std::erase_if(kept_, [&](const std::unique_ptr<PlaybackParameters>& kept) {
    return kept->id < in_use && kept.get() != pending;
  });
  return kept_.size();
}

std::string ParameterMailbox::description(int id) const {
  for (const auto& kept : kept_) {
    if (kept->id == id) return kept->description;
  }
  return "";
}

const PlaybackParameters* ParameterMailbox::take() noexcept {
  PlaybackParameters* newest = pending_.exchange(nullptr, std::memory_order_acq_rel);
  if (!newest) return nullptr;
  taken_time_s_.store(monotonic_now_s(), std::memory_order_release);
  in_use_id_.store(newest->id, std::memory_order_release);
  return newest;
}

}  // namespace doorbench::haptic
