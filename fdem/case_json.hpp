// fdem/case_json.hpp: the resolved case as JSON, for `fdem check --json` (fdem-tools take every case value from it
// instead of reading the TOML file themselves).
#pragma once

#include <toml++/toml.h>

#include <string>
#include <vector>

#include "fdem/case.hpp"
#include "fdem/output.hpp"

namespace fdem {

// The case file's TOML tree with the --set / --unset overrides applied in order, exactly as load_case applies them
// (fdem/case.cpp). Throws InputError as load_case does (no such file, TOML syntax error, a bad --set or --unset).
toml::table resolved_case_tree(const std::string& path, const std::vector<std::string>& overrides);

// A TOML node as JSON: tables as objects (keys in toml++'s order), arrays as arrays, strings, integers and floats as
// themselves (a non-finite float as null), booleans, and dates and times as their TOML text.
Json toml_to_json(const toml::node& node);

// The values the engine uses, defaults applied (the "resolved" object of fdem check --json): case name and
// thickness, geometry (type, mesh sizes, the mesh file), numerics, materials, interfaces, monitors, stages (with the
// damping each stage runs with: local, contact and mass damping are kept by later stages that do not set them),
// output intervals, the load-displacement curve and its sign, the [reference] and the files the case reads. Lengths in
// m, times in s, stresses in Pa, as in the case file; a value that is not given and has no default is null.
Json resolved_values_json(const CaseSpec& spec);

}  // namespace fdem
