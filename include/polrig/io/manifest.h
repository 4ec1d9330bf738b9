#pragma once
// Every dataset's manifest.yaml: enough to reproduce it — the rig file's text, the overrides,
// the complete effective rig, the seed, the program version and git revision, the command,
// and the schema version of each file. No timestamps: identical runs give identical folders.
#include <filesystem>
#include <optional>
#include <utility>
#include <string>
#include <vector>

#include "polrig/io/rig_yaml.h"

namespace polrig {

struct DatasetFile {
  std::string name;         // relative to the dataset folder
  int schema = 1;           // bumped whenever the file's columns change meaning
  std::string description;
};

struct Manifest {
  std::string command;             // the polrig command line, shell-quoted
  const LoadedRig* rig = nullptr;  // null for commands that take no rig
  std::vector<DatasetFile> files;  // plots.gp is added when the folder holds one
  std::vector<std::string> inputs = {};  // data files read (calibrate, apply)
  std::optional<std::string> working_directory = {};  // null: the current one (a resumed run gives its first's)
  // The traced sphere solved or loaded, and its cache file (`light:`); null: the rig's light's
  // origin(), if any (polrig trace, which has no rig, sets it).
  std::optional<LightOrigin> light = {};
};

// Writes DIR/manifest.yaml (with `light:` when the light has an origin, source.h's LightOrigin)
// and, when there is a rig, DIR/rig.yaml (the effective rig).
void write_manifest(const std::filesystem::path& dir, const Manifest& manifest);

// The manifest's fields as (name, text) pairs, for a file that carries its own (sweep.h5's
// attributes): the same values as manifest.yaml but the list of files and `light:` (a data file
// holds the same bits whether its sphere was solved or loaded); a list (overrides,
// inputs) as one line per item; the rig file's text exactly as read, or as rig_text_base64 when
// it is not UTF-8.
std::vector<std::pair<std::string, std::string>> manifest_fields(const Manifest& manifest);
// The working directory a manifest records.
std::string manifest_working_directory(const Manifest& manifest);

}  // namespace polrig
