// enum_option.h - one command-line option that takes a spelling of a libvff enum (spelling.h), and
// the choice every option group makes about the values of its options left unset.
//
//   vff::cli::EnumOption<vff::Codec> codec{"--codec", vff::vff::kCodecs, vff::Codec::kStored};
//   codec.add(app, "block codec")->capture_default_str();   // --help: TEXT:{stored,zstd} [stored]
//   ... after vff::cli::parse():  w.codec = codec.value();
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <utility>

#include "vff/spelling.h"

namespace vff::cli {

// Where an option group's options left off the command line take their values from.
enum class Defaults {
  kTool,   // the tool's own, shown in --help (vff-bake: a new field)
  kInput,  // the input file's (vff-convert: a rewritten field); --help says "default: the input's"
};

// An option whose argument is one of `spellings` (checked by CLI::IsMember at parse time, so an
// unknown word is a usage error that lists the words). CLI11 keeps a reference to the text, so an
// EnumOption stays where it is once added (no copies, no moves).
template <typename E>
class EnumOption {
 public:
  // `initial`: the value when the option is not given (none: value() is only for a given option).
  EnumOption(std::string flags, Spellings<E> spellings, std::optional<E> initial = std::nullopt)
      : flags_(std::move(flags)), spellings_(spellings), text_(initial ? spellings.name(*initial) : "") {}
  EnumOption(const EnumOption&) = delete;
  EnumOption& operator=(const EnumOption&) = delete;

  CLI::Option* add(CLI::App& app, const std::string& description) {
    option_ = app.add_option(flags_, text_, description)->check(CLI::IsMember(spellings_.all()));
    return option_;
  }
  // The option is on the command line.
  bool given() const { return option_ != nullptr && option_->count() > 0; }
  // The value given, else the initial one (after a successful parse; see the constructor).
  E value() const { return *spellings_.parse(text_); }
  // The value given, or nothing.
  std::optional<E> ifGiven() const { return given() ? std::optional<E>(value()) : std::nullopt; }

 private:
  std::string flags_;
  Spellings<E> spellings_;
  std::string text_;
  CLI::Option* option_ = nullptr;
};

}  // namespace vff::cli
