#pragma once
// The doors the preference scale ranks, as parameter files: `campaign analyze` writes one
// per variant whose rendered parameters the trials table carries (the first_parameters and
// second_parameters columns `campaign run` writes, "J=1.14 k=40 ..."), as
// OUT/variants/NAME.json, and names it in the variant's preference_scale row ("file", relative
// to analysis.json's folder). `spec --campaign` takes the favourite's file as the TO-BE feel
// (analysis/design/panel_spec.h).
//
// No variant gets a file when the table has no parameter columns (a table written by hand:
// one note says so); a variant gets none when none of its rows carries its parameters, when the
// rendered names are not all of one model's (sensory or physical) parameters, or when two rows
// render it differently: the note says which and why.
//
// Errors: none thrown for the table's content (a variant without a file is a note); the
// JSON must hold analyze_trials' preference_scale array when it has the key.
// Thread safety: free functions without shared state; write_variant_files writes files.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/model/door_model.h"
#include "study/trials_table.h"

namespace doorbench::study {

// "J=1.14 k=40 ..." -> the door: the sensory reference door with every named value, or the
// physical one; nullopt when the names are not exactly one model's parameters or a value is
// not a number.
std::optional<DoorModel> door_from_rendered(std::string_view rendered);

// A file name for a variant: its name with every character outside [A-Za-z0-9._-] replaced
// by '_', "variants/" before and ".json" after.
std::string variant_file_name(std::string_view variant);

struct VariantFile {
  std::string variant;
  std::string file;  // relative to the analysis folder, e.g. "variants/heavier.json"
  std::string text;  // the parameter file (analysis/model/parameter_file.h)
};

struct VariantFiles {
  std::vector<VariantFile> files;
  std::vector<std::string> notes;  // variants without a file, and why
};

// True for a file name (without folder) that variant_file_name gives: "NAME.json". Only such
// files in the variants folder are taken for an earlier analysis's variant files.
bool is_variant_file(const std::string& name);

// Writes `variants`' files under `analysis_folder` (each atomically, making the variants folder
// when there are files) and removes the variant files an earlier analysis left there that this
// one does not write (docs/output-files.md, rule 5); other files there are left alone.
// Errors: OutputError naming a file that cannot be written or removed.
void write_variant_files(const std::filesystem::path& analysis_folder,
                         const VariantFiles& variants);

// The files for `analysis`'s preference_scale rows; sets each row's "file" and adds the notes
// to analysis["preference_fit"]["notes"] (made when missing). Nothing when the analysis has
// no preference scale.
VariantFiles variant_parameter_files(const TrialsTable& table, nlohmann::json& analysis);

}  // namespace doorbench::study
