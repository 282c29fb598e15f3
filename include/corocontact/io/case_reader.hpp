#pragma once
/// @file case_reader.hpp
/// @brief Reads a TOML case file (schema: docs/case_file.md) into a CaseSpec.

#include <corocontact/sim/case_spec.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace coro {

/// Parses a case file. Paths inside it are resolved relative to the case file's folder
/// (absolute paths are kept); files they name are not opened here.
/// @param[in] file  the .toml case file
/// @return the case, every default filled in; simulation.name defaults to the file's stem and
///         simulation.output_dir to `out/<name>`
/// @throws InputError for a missing or unreadable file, TOML syntax errors, unknown keys,
///         wrong types and out-of-range values; the message starts with `file:line:column`
///         and names the key and what was expected
CaseSpec read_case(const std::filesystem::path& file);

/// Same as read_case; `notes` also gets what the file sets that its analysis does not use
/// ("case.toml:3:1: simulation.steps is not used by a static analysis, ..."): a note, not an
/// error, since a case file may keep the keys of both analyses.
CaseSpec read_case(const std::filesystem::path& file, std::vector<std::string>& notes);

/// Same as read_case, from text already in memory; `file` is used for messages and to
/// resolve relative paths.
CaseSpec parse_case(const std::string& text, const std::filesystem::path& file);

/// Same as parse_case, with the notes of read_case(file, notes).
CaseSpec parse_case(const std::string& text, const std::filesystem::path& file, std::vector<std::string>& notes);

} // namespace coro
