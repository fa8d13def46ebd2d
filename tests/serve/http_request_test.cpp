// The request-head parser and the Range / If-None-Match helpers of `relief
// serve`, as pure functions.
#include <gtest/gtest.h>

#include "http_request.h"

namespace relief::serve {
namespace {

TEST(ParseRequestHead, EveryFieldCountsTheLastOneToo) {
  auto r = parse_request_head("GET /a HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->method, "GET");
  EXPECT_EQ(r->target, "/a");
  EXPECT_FALSE(r->keep_alive);
  r = parse_request_head("GET /a HTTP/1.1\r\nIf-None-Match:  \"e1\" \r\n\r\n");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->if_none_match, "\"e1\"");
  r = parse_request_head("GET /a HTTP/1.1\r\nrange: bytes=1-2\r\n\r\n");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->range, "bytes=1-2");
  EXPECT_TRUE(r->keep_alive);
}

TEST(ParseRequestHead, ConnectionTokensAndVersions) {
  EXPECT_FALSE(parse_request_head("GET / HTTP/1.0\r\n\r\n")->keep_alive);
  EXPECT_TRUE(parse_request_head("GET / HTTP/1.0\r\nConnection: Keep-Alive\r\n\r\n")->keep_alive);
  EXPECT_FALSE(
      parse_request_head("GET / HTTP/1.1\r\nConnection: keep-alive, CLOSE\r\n\r\n")->keep_alive);
  EXPECT_TRUE(parse_request_head("GET / HTTP/1.1\r\nContent-Length: 5\r\n\r\n")->has_body);
  EXPECT_TRUE(parse_request_head("GET / HTTP/1.1\r\nTransfer-Encoding: chunked\r\n\r\n")->has_body);
  EXPECT_FALSE(parse_request_head("GET / HTTP/1.1\r\nContent-Length: 0\r\n\r\n")->has_body);
}

TEST(ParseRequestHead, MalformedHeadsAreErrors) {
  for (const char* head :
       {"", "\r\n\r\n", "GET\r\n\r\n", "GET /\r\n\r\n", "GET / HTTP/2.0\r\n\r\n",
        "GET  HTTP/1.1\r\n\r\n", "G(T / HTTP/1.1\r\n\r\n", "GET / HTTP/1.1\r\nNoColon\r\n\r\n",
        "GET / HTTP/1.1\r\nName : v\r\n\r\n", "GET / HTTP/1.1\r\n folded\r\n\r\n",
        "GET / HTTP/1.1\r\nHost: x\r\n", "GET / HTTP/1.1\r\n\r\nextra",
        "GET /a\x01 HTTP/1.1\r\n\r\n"}) {
    SCOPED_TRACE(head);
    EXPECT_FALSE(parse_request_head(head));
  }
  EXPECT_FALSE(parse_request_head(std::string_view("GET / HTTP/1.1\r\nA: \0\r\n\r\n", 24)));
  EXPECT_FALSE(parse_request_head("GET / HTTP/1.1\r\nX: " + std::string(9000, 'a') + "\r\n\r\n"));
}

TEST(ResolveRange, SingleRangesOnly) {
  const auto partial = [](std::string_view v, uint64_t size, uint64_t a, uint64_t b) {
    const RangeAnswer r = resolve_range(v, size);
    return r.kind == RangeKind::partial && r.range.first == a && r.range.last == b;
  };
  EXPECT_TRUE(partial("bytes=0-9", 100, 0, 9));
  EXPECT_TRUE(partial("bytes=90-200", 100, 90, 99));
  EXPECT_TRUE(partial("bytes=10-", 100, 10, 99));
  EXPECT_TRUE(partial("bytes=-10", 100, 90, 99));
  EXPECT_TRUE(partial("bytes=-1000", 100, 0, 99));
  EXPECT_EQ(resolve_range("bytes=100-", 100).kind, RangeKind::unsatisfiable);
  EXPECT_EQ(resolve_range("bytes=-0", 100).kind, RangeKind::unsatisfiable);
  EXPECT_EQ(resolve_range("bytes=0-", 0).kind, RangeKind::unsatisfiable);
  for (const char* ignored : {"bytes=0-1,3-4", "items=0-1", "bytes=5-2", "bytes=a-b", "bytes=-",
                              "bytes=1", "bytes=99999999999999999999-"}) {
    SCOPED_TRACE(ignored);
    EXPECT_EQ(resolve_range(ignored, 100).kind, RangeKind::whole);
  }
}

TEST(IfNoneMatch, StarListsAndWeakTags) {
  EXPECT_TRUE(if_none_match_matches("*", "\"a\""));
  EXPECT_TRUE(if_none_match_matches("\"b\", \"a\"", "\"a\""));
  EXPECT_TRUE(if_none_match_matches("W/\"a\"", "\"a\""));
  EXPECT_FALSE(if_none_match_matches("\"b\"", "\"a\""));
  EXPECT_FALSE(if_none_match_matches("", "\"a\""));
}

}  // namespace
}  // namespace relief::serve
