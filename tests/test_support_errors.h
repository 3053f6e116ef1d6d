// EXPECT_NOVAPHY_ERROR(statement, text): the statement throws novaphy::Error whose message contains text
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "engine/model/error.h"

#define EXPECT_NOVAPHY_ERROR(statement, text)                                                    \
  do {                                                                                           \
    try {                                                                                        \
      statement;                                                                                 \
      ADD_FAILURE() << #statement " did not throw";                                              \
    } catch (const ::novaphy::Error& e) {                                                        \
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << "message: " << e.what(); \
    }                                                                                            \
  } while (0)
