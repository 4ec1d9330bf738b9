#pragma once
// Every dataset's manifest.yaml: enough to reproduce it — the rig file's text, the overrides,
// the complete effective rig, the seed, the program version and git revision, the command,
// and the schema version of each file. No timestamps: identical runs give identical folders.
#include <filesystem>
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
};

// Writes DIR/manifest.yaml and, when there is a rig, DIR/rig.yaml (the effective rig).
void write_manifest(const std::filesystem::path& dir, const Manifest& manifest);

}  // namespace polrig
