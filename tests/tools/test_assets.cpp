// Assets: the viewer's page files, embedded at build time and found by exact name only.
#include "whiskeye/viewer/assets.h"

#include <gtest/gtest.h>

#include <string_view>

namespace whiskeye::viewer {
namespace {

TEST(Assets, ThePageIsEmbeddedAndServedByExactNameOnly) {
  const Asset* index = find_asset("/");
  ASSERT_NE(index, nullptr);
  EXPECT_EQ(index->path, "/index.html");
  EXPECT_EQ(index->content_type, "text/html; charset=utf-8");
  EXPECT_NE(index->body.find("/viewer.js"), std::string_view::npos);
  ASSERT_NE(find_asset("/viewer.js"), nullptr);
  ASSERT_NE(find_asset("/viewer.css"), nullptr);
  EXPECT_EQ(find_asset("/viewer.js")->content_type, "text/javascript; charset=utf-8");
  for (const char* path : {"/../etc/passwd", "/%2e%2e/%2e%2e/etc/passwd", "/etc/passwd", "//index.html",
                           "/./index.html", "/index.html/", "index.html", "/INDEX.HTML", "/viewer.js/../index.html",
                           "/index.html%00", "", "/web/index.html", "/embed_assets.cmake"}) {
    EXPECT_EQ(find_asset(path), nullptr) << path;
  }
  EXPECT_EQ(find_asset(std::string_view("/index.html\0.png", 16)), nullptr);
  for (const Asset& a : embedded_assets()) {
    EXPECT_EQ(a.body.find("http://"), std::string_view::npos) << a.path << " loads nothing from elsewhere";
    EXPECT_EQ(a.body.find("https://"), std::string_view::npos) << a.path;
  }
}

}  // namespace
}  // namespace whiskeye::viewer
