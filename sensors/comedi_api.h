#pragma once
// The one seam between doorbench and comedilib: every comedilib call the comedi backend
// and `doorbench devices` make goes through a ComediApi, a table of function pointers
// with comedilib's own signatures. Two tables exist:
//   - linked_comedilib(): Debian's libcomedi (package libcomedi-dev), linked in;
//   - load_comedi_library(path): the same names looked up with dlopen/dlsym in another
//     shared library, e.g. the device emulator tests/comedi_emulator (which implements
//     them with comedilib's documented behaviour, on no hardware).
// selected_comedi_api() picks the second when $DOORBENCH_COMEDI_LIBRARY names a library.
//
// Reading a command's data is read(2) on comedi_fileno() for the real library; a library
// that exports `doorbench_comedi_read` (the emulator does, to give EPIPE and EOF as the
// kernel does) is read through that instead. See docs/comedi.md.
#include <comedilib.h>
#include <sys/types.h>

#include <filesystem>
#include <string>

namespace doorbench::sensors {

struct ComediApi {
  std::string name;  // "libcomedi (linked)" or the loaded library's path

  comedi_t* (*open)(const char* path) = nullptr;
  int (*close)(comedi_t* device) = nullptr;
  int (*errno_value)(void) = nullptr;  // comedi_errno
  const char* (*strerror)(int error) = nullptr;
  const char* (*get_driver_name)(comedi_t* device) = nullptr;
  const char* (*get_board_name)(comedi_t* device) = nullptr;
  int (*get_n_subdevices)(comedi_t* device) = nullptr;
  int (*get_subdevice_type)(comedi_t* device, unsigned subdevice) = nullptr;
  int (*find_subdevice_by_type)(comedi_t* device, int type, unsigned start) = nullptr;
  int (*get_subdevice_flags)(comedi_t* device, unsigned subdevice) = nullptr;
  int (*get_n_channels)(comedi_t* device, unsigned subdevice) = nullptr;
  lsampl_t (*get_maxdata)(comedi_t* device, unsigned subdevice, unsigned channel) = nullptr;
  int (*get_n_ranges)(comedi_t* device, unsigned subdevice, unsigned channel) = nullptr;
  comedi_range* (*get_range)(comedi_t* device, unsigned subdevice, unsigned channel,
                             unsigned range) = nullptr;
  int (*get_buffer_size)(comedi_t* device, unsigned subdevice) = nullptr;
  int (*command_test)(comedi_t* device, comedi_cmd* command) = nullptr;
  int (*command)(comedi_t* device, comedi_cmd* command) = nullptr;
  int (*internal_trigger)(comedi_t* device, unsigned subdevice, unsigned trignum) = nullptr;
  int (*cancel)(comedi_t* device, unsigned subdevice) = nullptr;
  int (*fileno)(comedi_t* device) = nullptr;
  double (*to_phys)(lsampl_t data, comedi_range* range, lsampl_t maxdata) = nullptr;
  char* (*get_default_calibration_path)(comedi_t* device) = nullptr;  // free() the result
  comedi_calibration_t* (*parse_calibration_file)(const char* path) = nullptr;
  void (*cleanup_calibration)(comedi_calibration_t* calibration) = nullptr;
  int (*get_softcal_converter)(unsigned subdevice, unsigned channel, unsigned range,
                               enum comedi_conversion_direction direction,
                               const comedi_calibration_t* calibration,
                               comedi_polynomial_t* polynomial) = nullptr;
  double (*to_physical)(lsampl_t data, const comedi_polynomial_t* polynomial) = nullptr;
  // Blocking read of the running command's data, read(2)'s contract: bytes read, 0 at
  // the end of the acquisition, −1 with errno set (EPIPE: the buffer overran).
  ssize_t (*read)(comedi_t* device, void* buffer, size_t bytes) = nullptr;

  // The last comedilib error as text: "No such file or directory".
  std::string last_error() const;
};

// Debian's libcomedi, linked into doorbench.
const ComediApi& linked_comedilib();

// Every function above looked up in the shared library at `path` (kept loaded for the
// life of the process). Throws std::runtime_error naming the path and the missing symbol.
const ComediApi& load_comedi_library(const std::filesystem::path& path);

// $DOORBENCH_COMEDI_LIBRARY's library when that is set and not empty, else the linked one.
const ComediApi& selected_comedi_api();

// comedilib's names for subdevice types (COMEDI_SUBD_AI → "analog input") and arefs.
std::string comedi_subdevice_type_name(int type);
std::string comedi_aref_name(unsigned aref);

}  // namespace doorbench::sensors
