#include "station/station_session.h"

namespace doorbench::station {

StationSession::StationSession(const StationRequest& request)
    : request_(request),
      scene_(request.scene_file.empty() ? default_scene() : load_scene(request.scene_file)) {
  if (std::string problem = request_.window.validate(); !problem.empty()) {
    throw std::invalid_argument("station: " + problem);
  }
}

StationSession::~StationSession() {
  close();
}

void StationSession::open(const haptic::DoorSnapshotChannel& snapshot) {
  close();
  report_.reset();
  station_ = std::make_unique<Station>(scene_, snapshot, request_.window);
  station_->start();
}

void StationSession::close() {
  if (!station_) return;
  station_->stop();
  report_ = station_->report();
  station_.reset();
}

std::string StationSession::brief_report() const {
  if (station_) return station_->report().brief_report();
  return report_ ? report_->brief_report() : "station: not opened";
}

}  // namespace doorbench::station
