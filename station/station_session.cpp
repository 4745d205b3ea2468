#include "station/station_session.h"

namespace doorbench::station {

StationSession::StationSession(const StationRequest& request)
    : request_(request),
      scene_(request.scene_file.empty() ? default_scene() : load_scene(request.scene_file)) {
  if (std::string problem = request_.window.validate(); !problem.empty()) {
    throw std::invalid_argument("station: " + problem);
  }
  own_scene_name_ = request.scene_file.empty() ? "built-in" : request.scene_file.string();
  // The sound files are read now too: a bad one stops the run before the device moves.
  own_sounds_ = load_sound_samples(scene_.sounds, own_scene_name_);
  for (const std::filesystem::path& file : request.scenes) {
    if (scenes_.contains(file)) continue;
    auto scene = std::make_unique<Scene>(load_scene(file));
    scene->stereo = scene_.stereo;  // the screen's, whatever the staged scene says
    scene_sounds_.emplace(file, load_sound_samples(scene->sounds, file.string()));
    scenes_.emplace(file, std::move(scene));
  }
  for (const std::filesystem::path& file : request.sound_sets) {
    if (!sound_sets_.contains(file))
      sound_sets_.emplace(file, load_sound_samples(load_sound_set(file), file.string()));
  }
}

void StationSession::stage(const std::filesystem::path& scene_file,
                           const std::filesystem::path& sounds_file) {
  const Scene* scene = &scene_;
  const SoundSamples* sounds = &own_sounds_;
  if (!scene_file.empty()) {
    const auto found = scenes_.find(scene_file);
    if (found == scenes_.end())
      throw std::invalid_argument("station: scene " + scene_file.string() +
                                  " was not read at the start");
    scene = found->second.get();
    sounds = &scene_sounds_.at(scene_file);
  }
  if (!sounds_file.empty()) {
    const auto found = sound_sets_.find(sounds_file);
    if (found == sound_sets_.end())
      throw std::invalid_argument("station: sound set " + sounds_file.string() +
                                  " was not read at the start");
    sounds = &found->second;
  }
  staged_scene_ = scene;
  staged_sounds_ = sounds;
  if (station_) station_->show_scene(scene == &scene_ ? nullptr : scene);
}

std::string StationSession::staged_scene() const {
  return staged_scene_ == &scene_ ? own_scene_name_ : staged_scene_->source;
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
  if (staged_scene_ != &scene_) station_->show_scene(staged_scene_);
}

void StationSession::follow(const haptic::DoorSnapshotChannel& snapshot) {
  unfollow();
  if (station_) station_->follow(&snapshot);
  if (!request_.sound) {
    sound_report_.error = "--no-sound";
    return;
  }
  try {
    sound_ = std::make_unique<DoorSound>(*staged_scene_, *staged_sounds_, snapshot);
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
