#include "station/door_sound.h"

#include <AL/al.h>
#include <AL/alc.h>
#include <AL/alext.h>
#include <pthread.h>
#include <sched.h>
#include <sndfile.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "core/clock.h"
#include "core/number_format.h"

namespace doorbench::station {
namespace {

constexpr int kRateHz = 44100;
constexpr double kPollS = 0.002;
constexpr int kSoundFifoPriority = 20;

std::int16_t to_pcm(double x) {
  return std::int16_t(std::lround(std::clamp(x, -1.0, 1.0) * 32767.0));
}

SoundSample synthesise(double duration_s, const auto& wave) {
  SoundSample sample;
  sample.rate_hz = kRateHz;
  const auto n = std::size_t(duration_s * kRateHz);
  sample.frames.resize(n);
  std::minstd_rand noise(12345);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (std::size_t i = 0; i < n; ++i) {
    sample.frames[i] = to_pcm(wave(double(i) / kRateHz, uniform(noise)));
  }
  return sample;
}

std::string al_error_text(ALenum error) {
  const ALchar* text = alGetString(error);
  return text ? std::string(text) : "OpenAL error " + std::to_string(error);
}

}  // namespace

SoundSample synthesised_click() {
  // A metal catch: a 3.2 kHz ring and a noise burst, full at the first frame, gone in 20 ms.
  return synthesise(0.02, [](double t, double noise) {
    const double envelope = std::exp(-t / 0.003);
    return envelope * (0.55 * std::sin(2 * std::numbers::pi * 3200.0 * t) + 0.35 * noise);
  });
}

SoundSample synthesised_knock() {
  // A door against a rubber stop: a damped 140 Hz thump with a little 420 Hz body.
  return synthesise(0.15, [](double t, double noise) {
    const double envelope = std::exp(-t / 0.03) * std::min(1.0, t / 0.001);
    return envelope * (0.7 * std::sin(2 * std::numbers::pi * 140.0 * t) +
                       0.2 * std::sin(2 * std::numbers::pi * 420.0 * t) + 0.05 * noise);
  });
}

SoundSample synthesised_hinge() {
  // A soft hinge rub: noise with a slow 180 Hz creak, a whole number of periods so that the
  // loop joins without a click.
  return synthesise(1.0, [](double t, double noise) {
    const double creak = 0.5 + 0.5 * std::sin(2 * std::numbers::pi * 3.0 * t);
    return 0.25 * noise * (0.4 + 0.6 * creak) +
           0.2 * creak * std::sin(2 * std::numbers::pi * 180.0 * t);
  });
}

SoundSample read_sound_file(const std::filesystem::path& file) {
  SF_INFO info{};
  SNDFILE* sound = sf_open(file.string().c_str(), SFM_READ, &info);
  if (sound == nullptr) {
    throw SceneError(file.string() + ": cannot read the sound: " + sf_strerror(nullptr));
  }
  std::vector<float> interleaved(std::size_t(info.frames) * std::size_t(info.channels));
  const sf_count_t read = sf_readf_float(sound, interleaved.data(), info.frames);
  sf_close(sound);
  if (read <= 0 || info.channels <= 0) throw SceneError(file.string() + ": the sound is empty");
  SoundSample sample;
  sample.rate_hz = info.samplerate;
  sample.frames.resize(std::size_t(read));
  for (sf_count_t f = 0; f < read; ++f) {
    double sum = 0.0;
    for (int c = 0; c < info.channels; ++c) sum += interleaved[std::size_t(f * info.channels + c)];
    sample.frames[std::size_t(f)] = to_pcm(sum / info.channels);
  }
  return sample;
}

std::string SoundReport::brief_report() const {
  if (!error.empty()) return "sound: none (" + error + ")";
  std::string text = "sound: " + device + ", " + std::to_string(clicks) + " latch clicks, " +
                     std::to_string(knocks) + " stop knocks";
  if (latency_ms >= 0.0) text += ", output latency " + format_significant(latency_ms, 3) + " ms";
  text += fifo ? ", SCHED_FIFO" : ", best effort";
  return text;
}

struct DoorSound::Al {
  LPALCGETINTEGER64VSOFT get_integer64 = nullptr;  // ALC_SOFT_device_clock, when offered
  ALCdevice* device = nullptr;
  ALCcontext* context = nullptr;
  ALuint buffers[3] = {0, 0, 0};
  ALuint click = 0, knock = 0, hinge = 0;
};

SoundSamples load_sound_samples(const Sounds& s, std::string source) {
  SoundSamples samples;
  samples.source = std::move(source);
  samples.sounds = s;
  samples.click = s.latch_wav.empty() ? synthesised_click() : read_sound_file(s.latch_wav);
  samples.knock = s.stop_wav.empty() ? synthesised_knock() : read_sound_file(s.stop_wav);
  samples.hinge = s.hinge_wav.empty() ? synthesised_hinge() : read_sound_file(s.hinge_wav);
  return samples;
}

DoorSound::DoorSound(const Scene& scene, const haptic::DoorSnapshotChannel& snapshot)
    : DoorSound(scene, load_sound_samples(scene.sounds, scene.source), snapshot) {}

DoorSound::DoorSound(const Scene& scene, const SoundSamples& samples,
                     const haptic::DoorSnapshotChannel& snapshot)
    : scene_(scene),
      snapshot_(snapshot),
      sounds_(samples.sounds),
      click_(samples.click),
      knock_(samples.knock),
      hinge_(samples.hinge) {
  report_.sounds = samples.source;
}

DoorSound::~DoorSound() {
  stop();
}

void DoorSound::start() {
  if (al_) return;
  auto al = std::make_unique<Al>();
  al->device = alcOpenDevice(nullptr);
  if (al->device == nullptr)
    throw std::runtime_error(
        "cannot open an OpenAL output (OpenAL Soft's drivers setting, ALSOFT_DRIVERS, chooses "
        "one)");
  // A short mixing period (100 updates a second) keeps a click close to its tick on outputs
  // that take the hint.
  const ALCint attributes[] = {ALC_REFRESH, 100, 0};
  al->context = alcCreateContext(al->device, attributes);
  mixing_started_at_s_.store(monotonic_now_s());
  if (al->context == nullptr || alcMakeContextCurrent(al->context) == ALC_FALSE) {
    if (al->context) alcDestroyContext(al->context);
    alcCloseDevice(al->device);
    throw std::runtime_error("cannot make an OpenAL context on the output");
  }
  alGenBuffers(3, al->buffers);
  const SoundSample* samples[3] = {&click_, &knock_, &hinge_};
  for (int i = 0; i < 3; ++i) {
    alBufferData(al->buffers[i], AL_FORMAT_MONO16, samples[i]->frames.data(),
                 ALsizei(samples[i]->frames.size() * sizeof(std::int16_t)), samples[i]->rate_hz);
  }
  alGenSources(1, &al->click);
  alGenSources(1, &al->knock);
  alGenSources(1, &al->hinge);
  alSourcei(al->click, AL_BUFFER, ALint(al->buffers[0]));
  alSourcei(al->knock, AL_BUFFER, ALint(al->buffers[1]));
  alSourcei(al->hinge, AL_BUFFER, ALint(al->buffers[2]));
  alSourcef(al->click, AL_GAIN, float(sounds_.latch_gain));
  alSourcei(al->hinge, AL_LOOPING, AL_TRUE);
  alSourcef(al->hinge, AL_GAIN, 0.0f);
  const Camera& camera = scene_.camera;
  alListener3f(AL_POSITION, float(camera.position_m[0]), float(camera.position_m[1]),
               float(camera.position_m[2]));
  const ALfloat orientation[6] = {float(camera.target_m[0] - camera.position_m[0]),
                                  float(camera.target_m[1] - camera.position_m[1]),
                                  float(camera.target_m[2] - camera.position_m[2]),
                                  float(camera.up[0]),
                                  float(camera.up[1]),
                                  float(camera.up[2])};
  alListenerfv(AL_ORIENTATION, orientation);
  alSourcePlay(al->hinge);
  if (const ALenum error = alGetError(); error != AL_NO_ERROR) {
    alcMakeContextCurrent(nullptr);
    alcDestroyContext(al->context);
    alcCloseDevice(al->device);
    throw std::runtime_error("OpenAL: " + al_error_text(error));
  }
  report_.device = alcGetString(al->device, ALC_ALL_DEVICES_SPECIFIER)
                       ? alcGetString(al->device, ALC_ALL_DEVICES_SPECIFIER)
                       : "OpenAL output";
  if (alcIsExtensionPresent(al->device, "ALC_SOFT_device_clock") == ALC_TRUE) {
    al->get_integer64 = reinterpret_cast<LPALCGETINTEGER64VSOFT>(
        alcGetProcAddress(al->device, "alcGetInteger64vSOFT"));
    ALCint64SOFT clock_and_latency[2] = {0, 0};
    if (al->get_integer64 != nullptr) {
      al->get_integer64(al->device, ALC_DEVICE_CLOCK_LATENCY_SOFT, 2, clock_and_latency);
      report_.latency_ms = double(clock_and_latency[1]) * 1e-6;
    }
  }
  // The context is the polling thread's from here on.
  alcMakeContextCurrent(nullptr);
  al_ = std::move(al);
  quit_.store(false);
  thread_ = std::thread([this] { run(); });
  // Above the machine's ordinary work, below the render loop's tick (80) and a HapticMaster's
  // I/O thread: a click waits for neither a build nor a busy desktop. Best effort otherwise.
  sched_param parameter{};
  parameter.sched_priority = kSoundFifoPriority;
  report_.fifo = pthread_setschedparam(thread_.native_handle(), SCHED_FIFO, &parameter) == 0;
}

void DoorSound::place_sources(double theta_rad) {
  const Vec3 handle = door_point_at(scene_, scene_.handle_m, theta_rad);
  const Vec3& hinge = scene_.hinge_point_m;
  alSource3f(al_->click, AL_POSITION, float(handle[0]), float(handle[1]), float(handle[2]));
  alSource3f(al_->knock, AL_POSITION, float(hinge[0]), float(hinge[1]), float(hinge[2]));
  alSource3f(al_->hinge, AL_POSITION, float(hinge[0]), float(hinge[1]), float(hinge[2]));
}

void DoorSound::note_device_clock() {
  if (al_->get_integer64 == nullptr) return;
  ALCint64SOFT clock_ns = 0;
  al_->get_integer64(al_->device, ALC_DEVICE_CLOCK_SOFT, 1, &clock_ns);
  const double first_frame_s = monotonic_now_s() - double(clock_ns) * 1e-9;
  if (first_frame_s < mixing_started_at_s_.load(std::memory_order_relaxed)) {
    mixing_started_at_s_.store(first_frame_s, std::memory_order_release);
  }
}

void DoorSound::run() noexcept {
  alcMakeContextCurrent(al_->context);
  haptic::DoorSnapshot seen = snapshot_.read();
  const Sounds& sounds = sounds_;
  auto next = std::chrono::steady_clock::now();
  while (!quit_.load(std::memory_order_acquire)) {
    const haptic::DoorSnapshot now = snapshot_.read();
    note_device_clock();
    place_sources(now.theta_rad);
    if (now.unlatches + now.latches != seen.unlatches + seen.latches) {
      alSourceRewind(al_->click);
      alSourcePlay(al_->click);
      clicks_.fetch_add(1, std::memory_order_relaxed);
    }
    if (now.open_stop_hits + now.closed_stop_hits != seen.open_stop_hits + seen.closed_stop_hits) {
      const double loudness = std::min(1.0, now.last_stop_speed_rad_s / 2.0);
      alSourcef(al_->knock, AL_GAIN, float(sounds.stop_gain * std::max(0.2, loudness)));
      alSourceRewind(al_->knock);
      alSourcePlay(al_->knock);
      knocks_.fetch_add(1, std::memory_order_relaxed);
    }
    const double speed = std::min(1.0, std::abs(now.omega_rad_s) / sounds.hinge_full_speed_rad_s);
    alSourcef(al_->hinge, AL_GAIN, float(sounds.hinge_gain * speed));
    seen = now;
    next += std::chrono::microseconds(std::lround(kPollS * 1e6));
    const auto wake = std::max(next, std::chrono::steady_clock::now());
    next = wake;
    std::this_thread::sleep_until(wake);
  }
  alcMakeContextCurrent(nullptr);
}

void DoorSound::stop() {
  if (!al_) return;
  quit_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
  alcMakeContextCurrent(al_->context);
  alSourceStop(al_->hinge);
  const ALuint sources[3] = {al_->click, al_->knock, al_->hinge};
  alDeleteSources(3, sources);
  alDeleteBuffers(3, al_->buffers);
  alcMakeContextCurrent(nullptr);
  alcDestroyContext(al_->context);
  alcCloseDevice(al_->device);
  al_.reset();
}

SoundReport DoorSound::report() const {
  SoundReport report = report_;
  report.clicks = clicks_.load(std::memory_order_relaxed);
  report.knocks = knocks_.load(std::memory_order_relaxed);
  return report;
}

}  // namespace doorbench::station
