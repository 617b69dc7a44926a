// CAN socket: error-frame interpretation (pure) and clear failures. Real traffic is tested in the VM
// (tests/vm/scenario_whiskerd.sh), since this kernel has no CAN.
#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/error.h>

#include <array>

#include "whiskeye/can/can_socket.h"

using namespace whiskeye::can;

TEST(CanErrorFrames, BusOffIsReported) {
  const auto e = classify_error_frame(CAN_ERR_BUSOFF, {});
  EXPECT_TRUE(e.bus_off);
  EXPECT_EQ(next_bus_state(BusState::kErrorPassive, e), BusState::kBusOff);
}

TEST(CanErrorFrames, ControllerPassiveIsReported) {
  std::array<uint8_t, 8> d{};
  d[1] = CAN_ERR_CRTL_TX_PASSIVE;
  const auto e = classify_error_frame(CAN_ERR_CRTL, d);
  EXPECT_TRUE(e.passive);
  EXPECT_FALSE(e.bus_off);
  EXPECT_EQ(next_bus_state(BusState::kErrorActive, e), BusState::kErrorPassive);
}

TEST(CanErrorFrames, RestartRecoversFromBusOff) {
  const auto e = classify_error_frame(CAN_ERR_RESTARTED, {});
  EXPECT_EQ(next_bus_state(BusState::kBusOff, e), BusState::kErrorActive);
}

TEST(CanErrorFrames, WarningDoesNotDowngradePassive) {
  std::array<uint8_t, 8> d{};
  d[1] = CAN_ERR_CRTL_RX_WARNING;
  const auto e = classify_error_frame(CAN_ERR_CRTL, d);
  EXPECT_EQ(next_bus_state(BusState::kErrorActive, e), BusState::kErrorWarning);
  EXPECT_EQ(next_bus_state(BusState::kErrorPassive, e), BusState::kErrorPassive);
}

TEST(CanSocket, OpeningAMissingInterfaceThrowsNamingIt) {
  try {
    Socket s("nosuchcan9");
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nosuchcan9"), std::string::npos) << e.what();
  }
}

TEST(CanSocket, RejectsAnOverlongInterfaceName) {
  EXPECT_THROW(Socket("this_name_is_far_too_long_for_linux"), std::runtime_error);
}
