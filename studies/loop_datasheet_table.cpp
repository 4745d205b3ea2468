#include "studies/loop_datasheet_table.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "analysis/design/perceptual_tolerance.h"
#include "core/number_format.h"
#include "core/percentile.h"

namespace doorbench::datasheet {
namespace {

constexpr int kFieldCount = 28;

std::string quoted(const std::string& field) {
  if (field.find_first_of(",\"\n\r") == std::string::npos) return field;
  std::string out = "\"";
  for (char c : field) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string number(double value) {
  return printf_text("%.9g", value);
}

// The fields of one CSV line (quoted fields unquoted); false when a quote is left open.
bool split_line(const std::string& line, std::vector<std::string>& fields) {
  fields.assign(1, "");
  bool in_quotes = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (in_quotes) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        fields.back() += '"';
        ++i;
      } else if (c == '"') {
        in_quotes = false;
      } else {
        fields.back() += c;
      }
    } else if (c == '"') {
      in_quotes = true;
    } else if (c == ',') {
      fields.emplace_back();
    } else {
      fields.back() += c;
    }
  }
  return !in_quotes;
}

std::vector<std::string> record_fields(const RunRecord& r) {
  return {r.effect,
          std::to_string(r.size_rank),
          number(r.size),
          r.size_unit,
          std::to_string(r.draw),
          std::to_string(r.seed),
          r.hand,
          number(r.sample_rate_hz),
          r.sensors,
          std::to_string(r.strokes),
          r.conditions,
          r.loop_options,
          r.status,
          r.first_added,
          number(r.start_held_out_rad_s),
          number(r.final_held_out_rad_s),
          std::to_string(r.true_rank),
          number(r.true_share),
          number(r.true_z),
          number(r.true_screen_share),
          number(r.true_screen_z),
          r.true_verdict,
          r.best_name,
          number(r.best_share),
          number(r.best_z),
          r.parameters,
          number(r.cpu_s),
          number(r.wall_s)};
}

RunRecord record_from(const std::vector<std::string>& f) {
  RunRecord r;
  std::size_t i = 0;
  const auto text = [&] { return f[i++]; };
  const auto real = [&] { return std::stod(f[i++]); };
  const auto whole = [&] { return std::stoi(f[i++]); };
  r.effect = text();
  r.size_rank = whole();
  r.size = real();
  r.size_unit = text();
  r.draw = whole();
  r.seed = std::stoul(f[i++]);
  r.hand = text();
  r.sample_rate_hz = real();
  r.sensors = text();
  r.strokes = whole();
  r.conditions = text();
  r.loop_options = text();
  r.status = text();
  r.first_added = text();
  r.start_held_out_rad_s = real();
  r.final_held_out_rad_s = real();
  r.true_rank = whole();
  r.true_share = real();
  r.true_z = real();
  r.true_screen_share = real();
  r.true_screen_z = real();
  r.true_verdict = text();
  r.best_name = text();
  r.best_share = real();
  r.best_z = real();
  r.parameters = text();
  r.cpu_s = real();
  r.wall_s = real();
  return r;
}

// The runs of one table row: an effect at one size (or the clean recordings).
struct Row {
  std::string effect;
  int size_rank = 0;
  double size = 0.0;
  std::string size_unit, loop_options;
  std::vector<const RunRecord*> runs;
};

std::vector<Row> rows_of(const std::vector<RunRecord>& records) {
  std::vector<Row> rows;
  for (const RunRecord& r : records) {
    auto row = std::find_if(rows.begin(), rows.end(), [&](const Row& x) {
      return x.effect == r.effect && x.size_rank == r.size_rank && x.size == r.size;
    });
    if (row == rows.end()) {
      rows.push_back({r.effect, r.size_rank, r.size, r.size_unit, r.loop_options, {}});
      row = rows.end() - 1;
    }
    row->runs.push_back(&r);
  }
  // Effects in order of first appearance, each effect's sizes small to large.
  std::vector<std::string> order;
  for (const Row& row : rows) {
    if (std::find(order.begin(), order.end(), row.effect) == order.end())
      order.push_back(row.effect);
  }
  std::stable_sort(rows.begin(), rows.end(), [&](const Row& a, const Row& b) {
    const auto ia = std::find(order.begin(), order.end(), a.effect) - order.begin();
    const auto ib = std::find(order.begin(), order.end(), b.effect) - order.begin();
    return ia != ib ? ia < ib : a.size < b.size;
  });
  return rows;
}

bool ok(const RunRecord& r) {
  return r.status == "ok";
}

// "d_s +0.012 (+0.3 %), w_s ...": the mean deviation from the truth over the runs that
// found the effect first; and "d_s 18/19, ...": how many of their ±1.96 u intervals hold it.
void recovery_cells(const Row& row, std::string& bias, std::string& coverage) {
  std::map<std::string, std::vector<ParameterRecovery>> by_name;
  std::vector<std::string> order;
  for (const RunRecord* r : row.runs) {
    if (!ok(*r) || r->first_added != r->effect) continue;
    for (const ParameterRecovery& p : parse_parameters(r->parameters)) {
      if (!by_name.count(p.name)) order.push_back(p.name);
      by_name[p.name].push_back(p);
    }
  }
  bias.clear();
  coverage.clear();
  for (const std::string& name : order) {
    const std::vector<ParameterRecovery>& ps = by_name[name];
    double sum = 0.0;
    int covered = 0, with_u = 0;
    for (const ParameterRecovery& p : ps) {
      sum += p.value - p.truth;
      if (std::isfinite(p.uncertainty)) {
        ++with_u;
        if (std::abs(p.value - p.truth) <= 1.959963984540054 * p.uncertainty) ++covered;
      }
    }
    const double mean = sum / static_cast<double>(ps.size());
    const double truth = ps.front().truth;
    if (!bias.empty()) bias += ", ";
    bias += name + " " + printf_text("%+.3g", mean);
    if (truth != 0.0) bias += printf_text(" (%+.1f %%)", 100.0 * mean / truth);
    if (with_u == 0) continue;  // held fixed (e.g. end_stop.beta_e)
    if (!coverage.empty()) coverage += ", ";
    coverage += name + " " + std::to_string(covered) + "/" + std::to_string(with_u);
    const int undetermined = static_cast<int>(ps.size()) - with_u;
    if (undetermined > 0) coverage += " (" + std::to_string(undetermined) + " undetermined)";
  }
  if (bias.empty()) bias = "—";
  if (coverage.empty()) coverage = "—";
}

// Why the runs that missed the effect missed it, from the true effect's verdict in the first
// examination: "share < 1 % 7, z < 4 3, rejected 2, lost 1" (lost: it qualified, another
// effect's refit did better; ranked below the refits: refit_candidates better-ranked ones were
// refitted instead).
std::string miss_reasons(const Row& row) {
  std::map<std::string, int> counts;
  const std::vector<std::string> order = {
      "share < 1 %", "z < 4", "ranked below the refits", "refit rejected", "qualified, another won",
      "other"};
  for (const RunRecord* r : row.runs) {
    if (!ok(*r) || r->first_added == r->effect) continue;
    const std::string& v = r->true_verdict;
    const auto starts = [&](const char* prefix) { return v.rfind(prefix, 0) == 0; };
    if (starts("not refitted: explains"))
      ++counts["share < 1 %"];
    else if (starts("not refitted: score z"))
      ++counts["z < 4"];
    else if (starts("not refitted: ranked below"))
      ++counts["ranked below the refits"];
    else if (starts("rejected"))
      ++counts["refit rejected"];
    else if (starts("qualifies"))
      ++counts["qualified, another won"];
    else
      ++counts["other"];
  }
  std::string out;
  for (const std::string& key : order) {
    if (counts[key] == 0) continue;
    if (!out.empty()) out += ", ";
    out.append(key).append(" ").append(std::to_string(counts[key]));
  }
  return out.empty() ? "—" : out;
}

// A row's runs that ended (`done`), those that failed, and every run's CPU time.
struct RowTally {
  std::vector<const RunRecord*> done;
  int failed = 0;
  std::vector<double> cpu;
};

RowTally tally(const Row& row) {
  RowTally t;
  for (const RunRecord* r : row.runs) {
    t.cpu.push_back(r->cpu_s);
    if (ok(*r)) {
      t.done.push_back(r);
    } else {
      ++t.failed;
    }
  }
  return t;
}

std::string detection_table(const std::vector<Row>& rows) {
  std::string out =
      "| effect | size | runs | found first (95 % interval) | another effect first | "
      "nothing added | failed | why missed (the true effect's verdict) | true effect's median z "
      "(second looks) | bias of the "
      "fitted parameters (mean, found-first runs) | ±1.96 u holds the truth | CPU per run, "
      "median (s) |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const Row& row : rows) {
    if (row.effect == "clean") continue;
    const RowTally t = tally(row);
    const int n = static_cast<int>(t.done.size()), failed = t.failed;
    int first = 0, other = 0, none = 0;
    std::vector<double> z;
    int second_looks = 0;
    for (const RunRecord* r : t.done) {
      z.push_back(r->true_z);
      second_looks += r->true_screen_z != 0.0;
      if (r->first_added == r->effect)
        ++first;
      else if (r->first_added == "none")
        ++none;
      else
        ++other;
    }
    std::string bias, coverage;
    recovery_cells(row, bias, coverage);
    out += "| " + row.effect + " | " + format_significant(row.size, 4) + " " + row.size_unit +
           " | " + std::to_string(n) + " | " + share_with_interval(first, n) + " | " +
           std::to_string(other) + " | " + std::to_string(none) + " | " + std::to_string(failed) +
           " | " + miss_reasons(row) + " | " + printf_text("%.1f (%d)", median(z), second_looks) +
           " | " + bias + " | " + coverage + " | " + printf_text("%.1f", median(t.cpu)) + " |\n";
  }
  return out;
}

// Per effect: its ladder and the smallest size found first in >= 90 % of the runs.
std::string threshold_table(const std::vector<Row>& rows) {
  std::string out =
      "| effect | sizes tried | smallest size found first in ≥ 90 % | loop options |\n"
      "|---|---|---|---|\n";
  std::vector<std::string> effects;
  for (const Row& row : rows) {
    if (row.effect != "clean" &&
        std::find(effects.begin(), effects.end(), row.effect) == effects.end()) {
      effects.push_back(row.effect);
    }
  }
  for (const std::string& effect : effects) {
    std::vector<const Row*> ladder;
    for (const Row& row : rows) {
      if (row.effect == effect) ladder.push_back(&row);
    }
    std::sort(ladder.begin(), ladder.end(),
              [](const Row* a, const Row* b) { return a->size < b->size; });
    std::string sizes, smallest = "none of those tried";
    for (const Row* row : ladder) {
      int n = 0, first = 0;
      for (const RunRecord* r : row->runs) {
        n += ok(*r);
        first += ok(*r) && r->first_added == effect;
      }
      if (!sizes.empty()) sizes += ", ";
      sizes += format_significant(row->size, 4);
      if (smallest == "none of those tried" && n > 0 && first >= 0.9 * n) {
        smallest = format_significant(row->size, 4) + " " + row->size_unit + " (" +
                   std::to_string(first) + "/" + std::to_string(n) + ")";
      }
    }
    out += "| " + effect + " | " + sizes + " " + ladder.front()->size_unit + " | " + smallest +
           " | " + ladder.front()->loop_options + " |\n";
  }
  return out;
}

std::string clean_table(const std::vector<Row>& rows) {
  std::string out =
      "| clean recordings | false additions (95 % interval) | effects added | failed | loop "
      "options | CPU per run, median (s) |\n|---|---|---|---|---|---|\n";
  for (const Row& row : rows) {
    if (row.effect != "clean") continue;
    const RowTally t = tally(row);
    const int n = static_cast<int>(t.done.size()), failed = t.failed;
    int added = 0;
    std::map<std::string, int> which;
    for (const RunRecord* r : t.done) {
      if (r->first_added != "none") {
        ++added;
        ++which[r->first_added];
      }
    }
    std::string names;
    for (const auto& [name, count] : which) {
      if (!names.empty()) names += ", ";
      names.append(name).append(" ").append(std::to_string(count));
    }
    out += "| " + std::to_string(n) + " | " + share_with_interval(added, n) + " | " +
           (names.empty() ? "—" : names) + " | " + std::to_string(failed) + " | " +
           row.loop_options + " | " + printf_text("%.1f", median(t.cpu)) + " |\n";
  }
  return out;
}

// The rate band of a sample rate, for the breakdown: "50–100 Hz" or "200–1000 Hz".
std::string rate_band(double rate_hz) {
  return rate_hz <= 100.0 ? "≤ 100 Hz" : "≥ 200 Hz";
}

// Found first (clean: nothing added) by hand, sensor set and rate band: k/n per column.
std::string breakdown_table(const std::vector<Row>& rows) {
  std::vector<std::string> columns;
  const auto add_column = [&](const std::string& c) {
    if (std::find(columns.begin(), columns.end(), c) == columns.end()) columns.push_back(c);
  };
  for (const Row& row : rows) {
    for (const RunRecord* r : row.runs) {
      if (ok(*r)) add_column(r->hand);
    }
  }
  std::sort(columns.begin(), columns.end());
  const std::size_t hands = columns.size();
  std::vector<std::string> sensors;
  for (const Row& row : rows) {
    for (const RunRecord* r : row.runs) {
      if (ok(*r) && std::find(sensors.begin(), sensors.end(), r->sensors) == sensors.end()) {
        sensors.push_back(r->sensors);
      }
    }
  }
  std::sort(sensors.begin(), sensors.end());
  for (const std::string& c : sensors) add_column(c);
  add_column("≤ 100 Hz");
  add_column("≥ 200 Hz");
  std::string out = "| effect | size |";
  std::string rule = "|---|---|";
  for (const std::string& c : columns) {
    out += " " + c + " |";
    rule += "---|";
  }
  out += "\n" + rule + "\n";
  for (const Row& row : rows) {
    out += "| " + row.effect + " (" + (row.effect == "clean" ? "nothing added" : "found first") +
           ") | " +
           (row.effect == "clean" ? "—" : format_significant(row.size, 4) + " " + row.size_unit) +
           " |";
    for (std::size_t c = 0; c < columns.size(); ++c) {
      int n = 0, k = 0;
      for (const RunRecord* r : row.runs) {
        if (!ok(*r)) continue;
        const std::string& key = c < hands                    ? r->hand
                                 : c < hands + sensors.size() ? r->sensors
                                                              : rate_band(r->sample_rate_hz);
        if (key != columns[c]) continue;
        ++n;
        k += row.effect == "clean" ? r->first_added == "none" : r->first_added == row.effect;
      }
      out += " " + std::to_string(k) + "/" + std::to_string(n) + " |";
    }
    out += "\n";
  }
  return out;
}

}  // namespace

std::string share_with_interval(int successes, int trials) {
  if (trials <= 0) return "0/0";
  const BinomialInterval interval = wilson_interval(successes, trials);
  return printf_text("%d/%d = %.0f %% (%.1f–%.1f %%)", successes, trials,
                     100.0 * successes / trials, 100.0 * interval.low, 100.0 * interval.high);
}

std::string run_csv(const std::vector<RunRecord>& records) {
  std::string out = std::string(kRunCsvHeader) + "\n";
  for (const RunRecord& r : records) {
    std::string line;
    for (const std::string& field : record_fields(r)) {
      if (!line.empty()) line += ',';
      line += quoted(field);
    }
    out += line + "\n";
  }
  return out;
}

std::vector<RunRecord> read_run_csv(const std::filesystem::path& path) {
  std::vector<RunRecord> records;
  std::ifstream in(path);
  if (!in) return records;
  const std::string name = path.filename().string();
  std::string line;
  std::vector<std::string> fields;
  for (int number = 1; std::getline(in, line); ++number) {
    if (number == 1) {
      if (line != kRunCsvHeader) {
        throw std::runtime_error(name + ": line 1: not a loop datasheet CSV (the header differs)");
      }
      continue;
    }
    if (line.empty()) continue;
    const std::string where = name + ": line " + std::to_string(number) + ": ";
    if (!split_line(line, fields)) throw std::runtime_error(where + "a quote is not closed");
    if (fields.size() != kFieldCount) {
      throw std::runtime_error(where + std::to_string(fields.size()) + " fields, expected " +
                               std::to_string(kFieldCount));
    }
    try {
      records.push_back(record_from(fields));
    } catch (const std::logic_error&) {  // std::stod and friends: not a number
      throw std::runtime_error(where + "a numeric field is not a number");
    }
  }
  return records;
}

std::vector<ParameterRecovery> parse_parameters(const std::string& field) {
  std::vector<ParameterRecovery> out;
  std::stringstream all(field);
  std::string item;
  while (std::getline(all, item, ';')) {
    if (item.empty()) continue;
    std::stringstream parts(item);
    std::string name, truth, value, u;
    if (!std::getline(parts, name, ':') || !std::getline(parts, truth, ':') ||
        !std::getline(parts, value, ':') || !std::getline(parts, u, ':')) {
      throw std::runtime_error("parameters: '" + item + "' is not name:truth:value:u");
    }
    out.push_back({name, std::stod(truth), std::stod(value), std::stod(u)});
  }
  return out;
}

std::string format_parameters(const std::vector<ParameterRecovery>& parameters) {
  std::string out;
  for (const ParameterRecovery& p : parameters) {
    if (!out.empty()) out += ";";
    out += p.name + ":" + number(p.truth) + ":" + number(p.value) + ":" + number(p.uncertainty);
  }
  return out;
}

std::string datasheet_tables(const std::vector<RunRecord>& records) {
  const std::vector<Row> rows = rows_of(records);
  return "### Detection and recovery by size\n\n" + detection_table(rows) +
         "\n### The smallest size found first\n\n" + threshold_table(rows) +
         "\n### False additions on clean recordings\n\n" + clean_table(rows) +
         "\n### By hand, sensor set and rate (found first; clean: nothing added)\n\n" +
         breakdown_table(rows);
}

}  // namespace doorbench::datasheet
