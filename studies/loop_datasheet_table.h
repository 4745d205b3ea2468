#pragma once
// The residual loop's datasheet (docs/residual-loop.md, "The datasheet"): one record per
// loop run (a catalogue effect at one size, or a clean recording, on one drawn recording),
// the CSV that stores them (so that a run can be resumed and re-tabulated without running
// the loop again), and the markdown tables made from them.
//
// CSV: a header line (kRunCsvHeader) then one line per run, fields separated by ',' and
// quoted with '"' (doubled inside) when they hold ',', '"' or a line break (RFC 4180).
// `parameters` holds the added effect's parameters as "name:truth:value:u" joined by ';'
// (u "nan" when the fit left the parameter undetermined or held it).
//
// Errors: read_run_csv throws std::runtime_error naming the file and line
// ("runs.csv: line 3: 25 fields, expected 26"; "runs.csv: line 1: not a loop datasheet CSV
// (the header differs)"). Thread safety: free functions without shared state.
#include <filesystem>
#include <string>
#include <vector>

namespace doorbench::datasheet {

// One loop run.
struct RunRecord {
  std::string effect;  // catalogue name, or "clean"
  int size_rank = 0;   // the size's place in the effect's ladder, from 1; 0 for clean
  double size = 0.0;   // the effect's amplitude in `size_unit` (d_s - d1 for stribeck); 0 clean
  std::string size_unit;
  int draw = 0;            // from 1; draw d uses the same recording conditions in every row
  unsigned long seed = 0;  // the draw's seed (conditions and recording)
  std::string hand;        // the recording conditions, as drawn
  double sample_rate_hz = 0.0;
  std::string sensors;
  int strokes = 0;                    // strokes in the prepared recording
  std::string conditions;             // RecordingConditions::describe()
  std::string loop_options;           // what differs from LoopOptions' defaults
  std::string status;                 // "ok", or "error: " and the exception's message
  std::string first_added;            // the loop's first added effect, or "none"
  double start_held_out_rad_s = 0.0;  // the start fit's held-out window RMSE
  double final_held_out_rad_s = 0.0;  // after the step (= start when nothing was added)
  // The true effect in the first examination (empty/0 for clean): its rank, linear share
  // and z, the second look's share and z (0 when not taken), and its verdict.
  int true_rank = 0;
  double true_share = 0.0, true_z = 0.0;
  double true_screen_share = 0.0, true_screen_z = 0.0;
  std::string true_verdict;
  // The best-ranked candidate of the first examination.
  std::string best_name;
  double best_share = 0.0, best_z = 0.0;
  std::string parameters;  // see the header comment
  double cpu_s = 0.0;      // CPU time of the run's thread (recording + loop)
  double wall_s = 0.0;
};

inline constexpr const char* kRunCsvHeader =
    "effect,size_rank,size,size_unit,draw,seed,hand,sample_rate_hz,sensors,strokes,"
    "conditions,loop_options,status,first_added,start_held_out_rad_s,final_held_out_rad_s,"
    "true_rank,true_share,true_z,true_screen_share,true_screen_z,true_verdict,best_name,"
    "best_share,best_z,parameters,cpu_s,wall_s";

// The CSV text of `records` (header included).
std::string run_csv(const std::vector<RunRecord>& records);
// Reads a CSV that run_csv wrote; a missing file gives no records.
std::vector<RunRecord> read_run_csv(const std::filesystem::path& path);

// One parameter of `RunRecord::parameters`.
struct ParameterRecovery {
  std::string name;
  double truth = 0.0, value = 0.0, uncertainty = 0.0;
};
std::vector<ParameterRecovery> parse_parameters(const std::string& field);
std::string format_parameters(const std::vector<ParameterRecovery>& parameters);

// The markdown tables: detection and recovery by effect and size, the smallest size found
// first in >= 90 % of the draws, the false additions on clean recordings with their Wilson
// 95 % interval, and the CPU per run. Rows follow the order of first appearance.
std::string datasheet_tables(const std::vector<RunRecord>& records);

// "k/n = p % (low–high %)": the share and its Wilson 95 % interval, one decimal.
std::string share_with_interval(int successes, int trials);

}  // namespace doorbench::datasheet
