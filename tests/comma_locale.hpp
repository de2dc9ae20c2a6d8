// The test fixture CommaLocale: the process's C locale set to one whose decimal point is a
// comma, as a Python session hosting the module may set (locale.setlocale; docs/python.md
// "Locales"), under which printf writes "0,66". Shared by the tests of every text that must
// keep its point (core/decimal.hpp and the messages built from it).
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <clocale>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace rendulic {

// A locale whose decimal point is a comma, compiled from Debian's locale sources (the locales
// package, which .ci/setup.sh installs) into the test's own folder: the machine's locales are
// not changed.
class CommaLocale : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists("/usr/share/i18n/locales/de_DE"))
      GTEST_SKIP() << "no locale sources (Debian package locales): cannot make a locale with a "
                      "decimal comma";
    const std::filesystem::path dir = std::filesystem::path(RENDULIC_TEST_TMP) / "locales";
    std::filesystem::create_directories(dir);
    if (!std::filesystem::exists(dir / "de_DE.UTF-8" / "LC_NUMERIC")) {
      // Made under a name of this process's and renamed: the test programs of several modules
      // run at once, and one must not read a locale another is still writing.
      const std::filesystem::path mine = dir / ("de_DE.UTF-8.tmp-" + std::to_string(::getpid()));
      const std::string command = "localedef -i de_DE -f UTF-8 '" + mine.string() + "' 2>&1";
      ASSERT_EQ(std::system(command.c_str()), 0) << command;
      std::error_code taken;  // another process renamed its copy first: keep that one
      std::filesystem::rename(mine, dir / "de_DE.UTF-8", taken);
      std::filesystem::remove_all(mine, taken);
    }
    ::setenv("LOCPATH", dir.c_str(), 1);
    ASSERT_NE(std::setlocale(LC_ALL, "de_DE.UTF-8"), nullptr);
    char text[16];
    std::snprintf(text, sizeof text, "%g", 0.66);
    ASSERT_STREQ(text, "0,66") << "the locale has no decimal comma";
  }
  void TearDown() override {
    std::setlocale(LC_ALL, "C");
    ::unsetenv("LOCPATH");
  }
};

}  // namespace rendulic
