#include "sensors/comedi_api.h"

#include <dlfcn.h>
#include <unistd.h>

#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>

namespace doorbench::sensors {

namespace {

ssize_t read_through_fileno(comedi_t* device, void* buffer, size_t bytes) {
  return ::read(comedi_fileno(device), buffer, bytes);
}

// A loaded library without doorbench_comedi_read: read(2) on its comedi_fileno. Only one
// such library can be in use at a time (function pointers carry no state).
int (*g_loaded_fileno)(comedi_t*) = nullptr;
ssize_t read_through_loaded_fileno(comedi_t* device, void* buffer, size_t bytes) {
  return ::read(g_loaded_fileno(device), buffer, bytes);
}

template <typename Function>
void bind(void* library, const std::filesystem::path& path, const char* symbol, Function& target) {
  dlerror();
  void* address = dlsym(library, symbol);
  if (address == nullptr) {
    throw std::runtime_error(path.string() + ": not a comedilib: it has no " + symbol);
  }
  target = reinterpret_cast<Function>(address);
}

}  // namespace

std::string ComediApi::last_error() const {
  const int error = errno_value();
  const char* text = strerror(error);
  return text ? std::string(text) : "comedi error " + std::to_string(error);
}

const ComediApi& linked_comedilib() {
  static const ComediApi api = [] {
    ComediApi a;
    a.name = "libcomedi (linked)";
    a.open = comedi_open;
    a.close = comedi_close;
    a.errno_value = comedi_errno;
    a.strerror = comedi_strerror;
    a.get_driver_name = comedi_get_driver_name;
    a.get_board_name = comedi_get_board_name;
    a.get_n_subdevices = comedi_get_n_subdevices;
    a.get_subdevice_type = comedi_get_subdevice_type;
    a.find_subdevice_by_type = comedi_find_subdevice_by_type;
    a.get_subdevice_flags = comedi_get_subdevice_flags;
    a.get_n_channels = comedi_get_n_channels;
    a.get_maxdata = comedi_get_maxdata;
    a.get_n_ranges = comedi_get_n_ranges;
    a.get_range = comedi_get_range;
    a.get_buffer_size = comedi_get_buffer_size;
    a.command_test = comedi_command_test;
    a.command = comedi_command;
    a.internal_trigger = comedi_internal_trigger;
    a.cancel = comedi_cancel;
    a.fileno = comedi_fileno;
    a.to_phys = comedi_to_phys;
    a.get_default_calibration_path = comedi_get_default_calibration_path;
    a.parse_calibration_file = comedi_parse_calibration_file;
    a.cleanup_calibration = comedi_cleanup_calibration;
    a.get_softcal_converter = comedi_get_softcal_converter;
    a.to_physical = comedi_to_physical;
    a.read = read_through_fileno;
    return a;
  }();
  return api;
}

const ComediApi& load_comedi_library(const std::filesystem::path& path) {
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<ComediApi>> loaded;
  const std::lock_guard lock(mutex);
  const std::string key = std::filesystem::absolute(path).string();
  if (auto found = loaded.find(key); found != loaded.end()) return *found->second;

  // RTLD_LOCAL: the library's comedi_* names do not replace the linked libcomedi's.
  void* library = dlopen(key.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (library == nullptr) {
    const char* why = dlerror();
    throw std::runtime_error(path.string() +
                             ": cannot load the comedi library: " + (why ? why : "unknown error"));
  }
  auto api = std::make_unique<ComediApi>();
  api->name = key;
  bind(library, path, "comedi_open", api->open);
  bind(library, path, "comedi_close", api->close);
  bind(library, path, "comedi_errno", api->errno_value);
  bind(library, path, "comedi_strerror", api->strerror);
  bind(library, path, "comedi_get_driver_name", api->get_driver_name);
  bind(library, path, "comedi_get_board_name", api->get_board_name);
  bind(library, path, "comedi_get_n_subdevices", api->get_n_subdevices);
  bind(library, path, "comedi_get_subdevice_type", api->get_subdevice_type);
  bind(library, path, "comedi_find_subdevice_by_type", api->find_subdevice_by_type);
  bind(library, path, "comedi_get_subdevice_flags", api->get_subdevice_flags);
  bind(library, path, "comedi_get_n_channels", api->get_n_channels);
  bind(library, path, "comedi_get_maxdata", api->get_maxdata);
  bind(library, path, "comedi_get_n_ranges", api->get_n_ranges);
  bind(library, path, "comedi_get_range", api->get_range);
  bind(library, path, "comedi_get_buffer_size", api->get_buffer_size);
  bind(library, path, "comedi_command_test", api->command_test);
  bind(library, path, "comedi_command", api->command);
  bind(library, path, "comedi_internal_trigger", api->internal_trigger);
  bind(library, path, "comedi_cancel", api->cancel);
  bind(library, path, "comedi_fileno", api->fileno);
  bind(library, path, "comedi_to_phys", api->to_phys);
  bind(library, path, "comedi_get_default_calibration_path", api->get_default_calibration_path);
  bind(library, path, "comedi_parse_calibration_file", api->parse_calibration_file);
  bind(library, path, "comedi_cleanup_calibration", api->cleanup_calibration);
  bind(library, path, "comedi_get_softcal_converter", api->get_softcal_converter);
  bind(library, path, "comedi_to_physical", api->to_physical);
  if (void* reader = dlsym(library, "doorbench_comedi_read")) {
    api->read = reinterpret_cast<ssize_t (*)(comedi_t*, void*, size_t)>(reader);
  } else {
    g_loaded_fileno = api->fileno;
    api->read = read_through_loaded_fileno;
  }
  return *loaded.emplace(key, std::move(api)).first->second;
}

const ComediApi& selected_comedi_api() {
  const char* library = std::getenv("DOORBENCH_COMEDI_LIBRARY");
  if (library != nullptr && *library != '\0') return load_comedi_library(library);
  return linked_comedilib();
}

std::string comedi_subdevice_type_name(int type) {
  switch (type) {
    case COMEDI_SUBD_UNUSED:
      return "unused";
    case COMEDI_SUBD_AI:
      return "analog input";
    case COMEDI_SUBD_AO:
      return "analog output";
    case COMEDI_SUBD_DI:
      return "digital input";
    case COMEDI_SUBD_DO:
      return "digital output";
    case COMEDI_SUBD_DIO:
      return "digital I/O";
    case COMEDI_SUBD_COUNTER:
      return "counter";
    case COMEDI_SUBD_TIMER:
      return "timer";
    case COMEDI_SUBD_MEMORY:
      return "memory";
    case COMEDI_SUBD_CALIB:
      return "calibration";
    case COMEDI_SUBD_PROC:
      return "processor";
    case COMEDI_SUBD_SERIAL:
      return "serial";
    case COMEDI_SUBD_PWM:
      return "PWM";
    default:
      return "type " + std::to_string(type);
  }
}

std::string comedi_aref_name(unsigned aref) {
  switch (aref) {
    case AREF_GROUND:
      return "ground";
    case AREF_COMMON:
      return "common";
    case AREF_DIFF:
      return "diff";
    case AREF_OTHER:
      return "other";
    default:
      return "aref " + std::to_string(aref);
  }
}

}  // namespace doorbench::sensors
