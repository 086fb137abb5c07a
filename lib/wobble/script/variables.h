// Script variables: `${NAME}` in a script is replaced by the value a sweep case (or
// `wobble run --param NAME=VALUE`) gives NAME, `${NAME:-DEFAULT}` by DEFAULT when none is
// given, so one script serves every case of a study and still runs on its own. Replacement is
// textual and happens before the interpreter reads a line, so a variable can stand for any
// word: a `set` value, a mode's stiffness, a ground constant, a seed, an object's file name.
#pragma once

#include <map>
#include <set>
#include <string>

namespace wobble::script {

// `text` with every ${NAME} and ${NAME:-DEFAULT} replaced. A variable without a value or a
// default, a `${` without its `}` or a malformed name is a formats::ParseError naming `file`
// and the line. Names are letters, digits and '_', not starting with a digit.
std::string ExpandVariables(const std::string& text, const std::map<std::string, std::string>& values,
                            const std::string& file);

// Whether `name` can be a variable's: letters, digits and '_', not starting with a digit.
bool IsVariableName(const std::string& name);

// The names `text` uses (with or without a default), for refusing a parameter no line uses.
std::set<std::string> VariablesUsed(const std::string& text, const std::string& file);

}  // namespace wobble::script
