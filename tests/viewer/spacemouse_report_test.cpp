// SPDX-License-Identifier: BSD-3-Clause
// tests/viewer/spacemouse_report_test.cpp -- 3Dconnexion HID reports, both layouts, as bytes a
// device sends
#include <gtest/gtest.h>

#include <vector>

#include "spacemouse_report.h"

namespace penumbra::viewer {
namespace {

using Bytes = std::vector<std::uint8_t>;
using Axes = std::array<std::int16_t, 3>;

TEST(SpaceMouseReport, OlderLayoutTranslation) {
  MotionState s;
  // +350, -12, 0 as little-endian int16.
  EXPECT_EQ(apply_report(Bytes{0x01, 0x5e, 0x01, 0xf4, 0xff, 0x00, 0x00}, s), ReportKind::translation);
  EXPECT_EQ(s.translation, (Axes{350, -12, 0}));
  EXPECT_EQ(s.rotation, (Axes{0, 0, 0}));
}

TEST(SpaceMouseReport, OlderLayoutRotationKeepsTranslation) {
  MotionState s;
  apply_report(Bytes{0x01, 0x5e, 0x01, 0xf4, 0xff, 0x00, 0x00}, s);
  // -100, 0, +200.
  EXPECT_EQ(apply_report(Bytes{0x02, 0x9c, 0xff, 0x00, 0x00, 0xc8, 0x00}, s), ReportKind::rotation);
  EXPECT_EQ(s.rotation, (Axes{-100, 0, 200}));
  EXPECT_EQ(s.translation, (Axes{350, -12, 0}));
}

TEST(SpaceMouseReport, ButtonsAsABitmask) {
  MotionState s;
  EXPECT_EQ(apply_report(Bytes{0x03, 0x01, 0x00}, s), ReportKind::buttons);
  EXPECT_EQ(s.buttons, 1u);
  apply_report(Bytes{0x03, 0x02, 0x00}, s);
  EXPECT_EQ(s.buttons, 2u);
  apply_report(Bytes{0x03, 0x03, 0x00}, s);
  EXPECT_EQ(s.buttons, 3u);
  // A device with many buttons: the second byte holds buttons 9 to 16.
  apply_report(Bytes{0x03, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00}, s);
  EXPECT_EQ(s.buttons, 0x100u);
  apply_report(Bytes{0x03, 0x00, 0x00}, s);
  EXPECT_EQ(s.buttons, 0u);
}

TEST(SpaceMouseReport, NewerCombinedLayout) {
  MotionState s;
  const Bytes combined{0x01, 0x5e, 0x01, 0xf4, 0xff, 0x00, 0x00,   // translation +350, -12, 0
                       0x00, 0x80, 0xff, 0x7f, 0x01, 0x00};        // rotation -32768, 32767, 1
  EXPECT_EQ(apply_report(combined, s), ReportKind::motion);
  EXPECT_EQ(s.translation, (Axes{350, -12, 0}));
  EXPECT_EQ(s.rotation, (Axes{-32768, 32767, 1}));
}

TEST(SpaceMouseReport, TruncatedAndUnknownReportsAreIgnored) {
  MotionState s;
  apply_report(Bytes{0x01, 0x01, 0x00, 0x02, 0x00, 0x03, 0x00}, s);
  apply_report(Bytes{0x03, 0x01}, s);
  const MotionState before = s;
  for (const Bytes& bad : {Bytes{}, Bytes{0x01}, Bytes{0x01, 0x5e, 0x01, 0xf4}, Bytes{0x02, 0x9c, 0xff, 0x00, 0x00, 0xc8},
                           Bytes{0x03}, Bytes{0x00, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06}, Bytes{0x04, 0x01, 0x00},
                           Bytes{0x17, 0x64, 0x00}, Bytes{0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff}}) {
    EXPECT_EQ(apply_report(bad, s), ReportKind::ignored) << bad.size() << " bytes, id " << (bad.empty() ? -1 : bad[0]);
    EXPECT_EQ(s.translation, before.translation);
    EXPECT_EQ(s.rotation, before.rotation);
    EXPECT_EQ(s.buttons, before.buttons);
  }
}

TEST(SpaceMouseReport, PaddedOlderReportIsStillTranslationOnly) {
  MotionState s;
  s.rotation = {5, 6, 7};
  EXPECT_EQ(apply_report(Bytes{0x01, 0x0a, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}, s), ReportKind::translation);
  EXPECT_EQ(s.translation, (Axes{10, 0, 0}));
  EXPECT_EQ(s.rotation, (Axes{5, 6, 7}));
}

}  // namespace
}  // namespace penumbra::viewer
