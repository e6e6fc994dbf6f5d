// An effect's target as a typed value: its one reader (ParseEffectTarget) and its one printer
// (TargetText). model-format.md "Effects" gives the forms.
#include <charconv>
#include <ostream>

#include "ema/model/effects.hpp"
#include "ema/model/model.hpp"

namespace ema::model {
namespace {

// (Helper names unique in the model target: it is a unity build.)

constexpr const char* kAllPointsText = "all_points";
constexpr const char* kPointsPrefix = "points:";

// What a kind's target may be, in words, for the reader's messages.
std::string ExpectedTargetWords(EffectKind kind) {
  switch (kind) {
    case EffectKind::kAddedMass:
      return "'all_points' or 'points:101,102' (test point ids separated by commas)";
    case EffectKind::kStiffnessScale:
      return "a spring group or FE part group ('joints'), one member of it ('joints/J3'), or a part in no group";
    case EffectKind::kMassScale:
      return "a body, an FE part group or a part in no group ('top'), or one part of a group ('deck/P3')";
    case EffectKind::kGroundSpring:
      return "a body ('top')";
    case EffectKind::kSeriesCompliance:
    case EffectKind::kOperatingPoint:
      break;
  }
  return "a spring group ('joints') or one member of it ('joints/J3')";
}

// One id of a points list: an integer, spaces around it allowed (as the reader always took it).
std::optional<int> PointIdOf(const std::string& item) {
  const auto first = item.find_first_not_of(" \t");
  if (first == std::string::npos) return std::nullopt;
  const auto last = item.find_last_not_of(" \t");
  const char* begin = item.data() + first;
  const char* end = item.data() + last + 1;
  if (*begin == '+' && end - begin > 1 && begin[1] != '-') ++begin;
  int id = 0;
  const auto [ptr, ec] = std::from_chars(begin, end, id);
  if (ec != std::errc() || ptr != end) return std::nullopt;
  return id;
}

}  // namespace

EffectTarget EffectTarget::Named(std::string name) {
  EffectTarget t;
  t.form = Form::kName;
  t.name = std::move(name);
  return t;
}

EffectTarget EffectTarget::MemberOf(std::string group, std::string member) {
  EffectTarget t;
  t.form = Form::kMember;
  t.name = std::move(group);
  t.member = std::move(member);
  return t;
}

EffectTarget EffectTarget::EveryMemberOf(std::string group) {
  EffectTarget t;
  t.form = Form::kEveryMember;
  t.name = std::move(group);
  return t;
}

EffectTarget EffectTarget::AllPoints() {
  EffectTarget t;
  t.form = Form::kAllPoints;
  return t;
}

EffectTarget EffectTarget::Points(std::vector<int> ids) {
  EffectTarget t;
  t.form = Form::kPoints;
  t.points = std::move(ids);
  return t;
}

EffectTarget EffectTarget::EveryPoint() {
  EffectTarget t;
  t.form = Form::kEveryPoint;
  return t;
}

std::string TargetText(const EffectTarget& t) {
  switch (t.form) {
    case EffectTarget::Form::kName:
      return t.name;
    case EffectTarget::Form::kMember:
      return t.name + "/" + t.member;
    case EffectTarget::Form::kEveryMember:
      return t.name + "/*";
    case EffectTarget::Form::kAllPoints:
      return kAllPointsText;
    case EffectTarget::Form::kPoints: {
      std::string text = kPointsPrefix;
      for (std::size_t i = 0; i < t.points.size(); ++i) text += (i ? "," : "") + std::to_string(t.points[i]);
      return text;
    }
    case EffectTarget::Form::kEveryPoint:
      return std::string(kPointsPrefix) + "*";
  }
  return t.name;
}

std::ostream& operator<<(std::ostream& out, const EffectTarget& target) { return out << TargetText(target); }

std::optional<EffectTarget> ParseEffectTarget(EffectKind kind, const std::string& text, std::string* error) {
  auto fail = [&](const std::string& why) -> std::optional<EffectTarget> {
    if (error) *error = why + "expected " + ExpectedTargetWords(kind);
    return std::nullopt;
  };
  if (Info(kind).acts_on == ActsOn::kPoints) {
    if (text == kAllPointsText) return EffectTarget::AllPoints();
    const std::string prefix = kPointsPrefix;
    if (text.compare(0, prefix.size(), prefix) != 0) return fail("");
    std::vector<int> ids;
    std::size_t from = prefix.size();
    while (true) {
      const std::size_t comma = text.find(',', from);
      const std::string item = text.substr(from, comma == std::string::npos ? std::string::npos : comma - from);
      const std::optional<int> id = PointIdOf(item);
      if (!id) return fail("bad point id '" + item + "': ");
      ids.push_back(*id);
      if (comma == std::string::npos) break;
      from = comma + 1;
    }
    return EffectTarget::Points(std::move(ids));
  }
  if (text.empty()) return fail("");
  const std::size_t slash = text.find('/');
  if (slash == std::string::npos) return EffectTarget::Named(text);
  const std::string group = text.substr(0, slash), member = text.substr(slash + 1);
  if (kind == EffectKind::kGroundSpring) return fail("a body's name has no '/': ");
  if (group.empty()) return fail("no group before '/': ");
  if (member.empty() || member == "*") return fail("no one member after '/': ");
  return EffectTarget::MemberOf(group, member);
}

}  // namespace ema::model
