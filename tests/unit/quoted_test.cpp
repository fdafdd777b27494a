// Quoted: client text in Errors and log lines stays short, escaped and valid UTF-8.
#include "server/common/quoted.h"

#include <gtest/gtest.h>

#include <string>

#include "tests/support/no_warnings.h"

namespace sim4cv {
namespace {

TEST(QuotedTest, ShortTextIsQuotedWhole) {
  EXPECT_EQ(Quoted("uav"), "'uav'");
  EXPECT_EQ(Quoted(""), "''");
  EXPECT_EQ(Quoted(std::string(64, 'a')), "'" + std::string(64, 'a') + "'");
}

TEST(QuotedTest, LongTextIsCutAndItsSizeGiven) {
  EXPECT_EQ(Quoted(std::string(65, 'a')), "'" + std::string(64, 'a') + "\xE2\x80\xA6' (65 bytes)");
  EXPECT_EQ(Quoted(std::string(60 << 20, 'b'), 3), "'bbb\xE2\x80\xA6' (62914560 bytes)");
}

TEST(QuotedTest, ControlCharactersAreEscaped) {
  EXPECT_EQ(Quoted("a\nb\x7f\x01"), "'a\\x0ab\\x7f\\x01'");
}

TEST(QuotedTest, NeverCutsAUtf8SequenceInTwo) {
  // "é" is two bytes: cut after 2 bytes of "aé…" the é goes whole or not at all.
  EXPECT_EQ(Quoted("a\xC3\xA9z", 2), "'a\xE2\x80\xA6' (4 bytes)");
  EXPECT_EQ(Quoted("a\xC3\xA9z", 3), "'a\xC3\xA9\xE2\x80\xA6' (4 bytes)");
}

}  // namespace
}  // namespace sim4cv
