#pragma once
// What `doorbench play --station` opens beside a playback (docs/station.md): the scene
// and its sound files (read first, so that a bad scene stops the run before the device
// moves), then, once the playback's render loop exists, the station's window and its sound,
// each on its own thread reading the loop's DoorSnapshotChannel. A station without an audio
// output plays on silent and says so in its report. close() ends both before the playback
// (and its snapshot) goes.
//
// For a run of trials (`ab`, `campaign run`) the window stays open from start() to close()
// and follows each presentation's playback (follow(), unfollow()); the sound is opened for
// each presentation and its counts add up over the run.
//
// Thread safety: one control thread.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "haptic/door_snapshot.h"
#include "station/door_sound.h"
#include "station/scene.h"
#include "station/station.h"

namespace doorbench::station {

struct StationRequest {
  std::filesystem::path scene_file;  // empty: the built-in dishwasher
  StationWindowOptions window;
  bool sound = true;
};

class StationSession {
 public:
  // Reads the scene; throws SceneError naming the file and key.
  explicit StationSession(const StationRequest& request);
  ~StationSession();

  const Scene& scene() const { return scene_; }
  // Opens the window reading `snapshot` (which must outlive close()); throws
  // std::runtime_error when it cannot (no display, no such display: the message says).
  void open(const haptic::DoorSnapshotChannel& snapshot);
  // Opens the window following no playback (the door rests closed); throws as open() does.
  void start();
  // The window and the sound follow `snapshot` (which must outlive unfollow()) from the next
  // frame; the sound's output opens now (a station without one plays on silent).
  void follow(const haptic::DoorSnapshotChannel& snapshot);
  // Stops following: the sound's output closes, the door rests closed.
  void unfollow();
  // Ends the window's thread; keeps its report.
  void close();
  // Two lines for the summary: frames, frame interval, stereo, any note; the sounds played.
  std::string brief_report() const;
  Station* station() { return station_.get(); }
  const Station* station() const { return station_.get(); }

 private:
  StationRequest request_;
  Scene scene_;
  std::unique_ptr<Station> station_;
  std::optional<StationReport> report_;
  std::unique_ptr<DoorSound> sound_;
  SoundReport sound_report_;
  std::uint64_t clicks_before_ = 0, knocks_before_ = 0;  // of earlier presentations
};

}  // namespace doorbench::station
