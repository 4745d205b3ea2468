#pragma once
// Reading TDMS files (NI's TDM Streaming format, as LabVIEW, SignalExpress and DAQmx logging
// write them) from NI's published description of the format, "TDMS File Format Internal
// Structure", without NI's libraries. User documentation: docs/tdms.md.
//
// Supported: TDMS 1.0 and 2.0 segments (lead-in "TDSm", version 4712 or 4713); metadata
// with new or appended object lists, raw data indexes
// given, repeated ("same as the previous segment", 0x00000000) or absent (0xFFFFFFFF);
// interleaved and non-interleaved raw data in whole chunks; channels of the integer types
// (I8…I64, U8…U64), SGL and DBL (with or without unit); string channels are skipped; every
// property type but the extended float; scaling properties of the Linear and Polynomial
// kinds (NI_Scaling_Status "unscaled"); time from wf_start_offset + i × wf_increment.
// DAQmx raw data (DAQmx logging's "TDMS raw" files: ToC flag kTocDAQmxRawData, raw data
// indexes 69 12 00 00 and 69 13 00 00): format-changing scalers (U8…I64, SGL, DBL at a byte
// offset in a raw buffer's stride) and digital line scalers (a bit: 0/1), several raw
// buffers (one per device) one after the other in each chunk; the channel's value is its
// last NI_Scale, where a scale without a Scale_Type is the scaler of that scale id, and a
// channel without scales is its one scaler's raw value. Each scaler's raw values are kept
// (TdmsChannel::daqmx_raw).
// Segments of either byte order: the ToC flags are little-endian, and kTocBigEndian makes
// everything after them big-endian (the lead-in's version and offsets, the metadata, the raw
// data; a time stamp's seconds come before its fractions).
// Refused, each by name: DAQmx scalers of other types or reading
// past their buffer, a segment mixing DAQmx and other raw data, channels of other data
// types, arrays of more than one dimension, raw data that is not a whole number of chunks,
// other scale types (Table, Thermocouple, RTD, ...).
// Values become doubles: exact for every type but I64/U64 beyond 2^53.
//
// Thread safety: free functions without shared state.
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "acquisition/session/import_units.h"
#include "acquisition/session/recording_csv.h"

namespace doorbench {

// A file that cannot be read, or a layout that is not supported: "PATH: segment N (byte B):
// what" (or "PATH: what" when no segment is to blame).
class TdmsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct TdmsProperty {
  std::string text;              // the value as text (time stamps as ISO 8601 UTC)
  std::optional<double> number;  // numeric types (and booleans as 0/1)
};

struct TdmsChannel {
  std::string group, name;     // unescaped
  std::string data_type;       // "I32", "DBL", ...; "" when the channel has no raw data
  std::vector<double> values;  // scaled when the file asks for scaling
  std::map<std::string, TdmsProperty> properties;
  std::string scaling;  // how the values were scaled ("" = as stored)
  // DAQmx raw data: each scaler's values as stored (digital lines as 0/1), by scale id; the
  // channel's values are these through its NI_Scale properties. Empty for other channels.
  std::map<std::uint32_t, std::vector<double>> daqmx_raw;
};

struct TdmsFile {
  std::map<std::string, TdmsProperty> file_properties;
  std::map<std::string, std::map<std::string, TdmsProperty>> group_properties;
  std::vector<TdmsChannel> channels;  // in the order they first appear
  int segments = 0;
  // The channel GROUP/NAME; nullptr when there is none.
  const TdmsChannel* find(const std::string& group, const std::string& name) const;
};

// Throws TdmsError (a layout that is not supported, a damaged file; "PATH: cannot open for
// reading" when it cannot be read; a Git LFS pointer in place of the file named as such,
// acquisition/session/lfs_pointer.h).
TdmsFile read_tdms(const std::filesystem::path& path);
TdmsFile parse_tdms(const std::vector<std::uint8_t>& bytes, const std::string& source);

// One item of `doorbench import --map`: TARGET=GROUP/CHANNEL. TARGET is force, angle, rate,
// time or an extra column name with a unit suffix (e.g. inclinometer_angle_rad). A name may
// hold any character: '\/', '\,', '\=' and '\\' stand for '/', ',', '=' and '\'; an
// unescaped '/' inside a name also works when only one of the ways to split GROUP/CHANNEL
// at its '/'s names a channel of the file ("07/09/2012 06:58:23 PM - Digital Input/Line 0").
struct TdmsMapItem {
  std::string target, group, channel;  // group and channel split at the first unescaped '/'
  std::string text;                    // GROUP/CHANNEL as given (escapes kept)
  // Every (group, channel) the text can mean, one per unescaped '/', the first first.
  std::vector<std::pair<std::string, std::string>> splits;
};
// "force=Load/Force,angle=Encoder/Angle"; throws std::invalid_argument naming the item.
std::vector<TdmsMapItem> parse_tdms_map(const std::string& text);
// A group or channel name as --map takes it: '/', ',', '=' and '\' escaped with '\'.
std::string escape_tdms_map_name(const std::string& name);
// The file's channels as --map names them, "Door/Force, Door/Angle" ("none" when empty).
std::string tdms_channel_list(const TdmsFile& file);

// How tdms_to_recording builds the recording beyond the map (doorbench import's options).
struct TdmsImportOptions {
  // import --keep-raw: also each mapped channel's DAQmx scalers as stored (daqmx_raw: ADC
  // counts, digital lines), as extra columns TARGET_raw ("force_raw"; an extra target's stem,
  // "incl_raw" for incl_V; the scaler id appended when a channel has several), each with a
  // metadata line tdms_raw_NAME saying which scaler of which channel it is; a channel without
  // DAQmx raw data adds no column.
  bool keep_raw = false;
  // import --rate-hz: > 0, the sample rate of channels without waveform timing (no
  // wf_increment): sample i at wf_start_offset + i / rate_hz (wf_start_offset 0 when
  // absent). A force channel whose wf_increment says another rate is refused; so is a time
  // channel in the map. 0: the waveform's timing.
  double rate_hz = 0.0;
  // import --scale, --calibration: targets whose channels hold a raw signal (volts); their
  // units are checked against the record (the channel's unit_string must be the record's
  // input unit, when it states one) instead of the target's, the raw values are kept and the
  // record goes to Recording::calibrations.
  std::vector<ImportConversion> conversions;
  // "" when usable, else the option at fault.
  std::string validate() const;
};

// The mapped channels as a recording: force and angle or rate are required, and no channel
// may be mapped twice; time from the `time` channel when mapped, else wf_start_offset + i ×
// wf_increment of the force channel (or i / options.rate_hz; every mapped channel must have
// as many values and the same wf_increment). Units are checked where the channel states one
// (unit_string: N for force, rad for angle, rad/s for rate; for a converted target, the
// record's input unit). The file's handle_radius_m property (file or group) becomes the
// recording's; mapped channels' properties, the file's and the force channel's
// wf_start_time (metadata tdms_wf_start_time, ISO 8601 UTC) go into the metadata. Throws
// TdmsError "SOURCE: ..." naming the target and channel and ending with the file's
// channels (tdms_channel_list).
Recording tdms_to_recording(const TdmsFile& file, const std::vector<TdmsMapItem>& map,
                            const std::string& source, const TdmsImportOptions& options = {});

}  // namespace doorbench
