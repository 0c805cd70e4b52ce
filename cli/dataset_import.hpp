// What `dataset import-colmap` and `dataset from-photos` share: the layout flag and the report of an import.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "data/import/colmap_import.hpp"

namespace mipnerf::cli {

// --layout auto | llff | transforms.
data::ImportLayout parse_import_layout(const std::string& value);

// What was imported, where, in which layout and why, and the command that trains on it.
void print_import(const data::ColmapImport& imported, const std::string& sparse_dir);

// `dataset from-photos`, a subcommand of `dataset` (cli/cmd_from_photos.cpp).
void register_from_photos(CLI::App& dataset);

}  // namespace mipnerf::cli
