#include "station/station_session.h"

namespace doorbench::station {

StationSession::StationSession(const StationRequest& request)
    : request_(request),
      scene_(request.scene_file.empty() ? default_scene() : load_scene(request.scene_file)) {
  if (std::string problem = request_.window.validate(); !problem.empty()) {
    throw std::invalid_argument("station: " + problem);
  }
  // The sound files are read now too: a bad one stops the run before the device moves.
  for (const std::filesystem::path* file :
       {&scene_.sounds.latch_wav, &scene_.sounds.stop_wav, &scene_.sounds.hinge_wav}) {
    if (!file->empty()) read_sound_file(*file);
  }
}

StationSession::~StationSession() {
  close();
}

void StationSession::open(const haptic::DoorSnapshotChannel& snapshot) {
  start();
  follow(snapshot);
}

void StationSession::start() {
  close();
  report_.reset();
  sound_report_ = {};
  clicks_before_ = knocks_before_ = 0;
  station_ = std::make_unique<Station>(scene_, request_.window);
  station_->start();
}

void StationSession::follow(const haptic::DoorSnapshotChannel& snapshot) {
  unfollow();
  if (station_) station_->follow(&snapshot);
  if (!request_.sound) {
    sound_report_.error = "--no-sound";
    return;
  }
  try {
    sound_ = std::make_unique<DoorSound>(scene_, snapshot);
    sound_->start();
  } catch (const std::runtime_error& error) {
    // Sight and touch go on without sound; the report says why it is silent.
    sound_.reset();
    sound_report_.error = error.what();
  }
}

void StationSession::unfollow() {
  if (station_) station_->follow(nullptr);
  if (!sound_) return;
  sound_->stop();
  sound_report_ = sound_->report();
  sound_.reset();
  clicks_before_ += sound_report_.clicks;
  knocks_before_ += sound_report_.knocks;
  sound_report_.clicks = clicks_before_;
  sound_report_.knocks = knocks_before_;
}

void StationSession::close() {
  unfollow();
  if (!station_) return;
  station_->stop();
  report_ = station_->report();
  station_.reset();
}

std::string StationSession::brief_report() const {
  const std::string sight = station_  ? station_->report().brief_report()
                            : report_ ? report_->brief_report()
                                      : std::string("station: not opened");
  SoundReport sound = sound_ ? sound_->report() : sound_report_;
  if (sound_) {
    sound.clicks += clicks_before_;
    sound.knocks += knocks_before_;
  }
  return sight + "\n" + sound.brief_report();
}

}  // namespace doorbench::station
