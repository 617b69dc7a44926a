// The browsers watching whiskeye-viewer: a bounded number of clients, each with a bounded queue of
// updates. A client that does not keep up (a slow link, a suspended tab) never holds the daemon or
// the other clients back and never makes memory grow: when its queue is full, the updates waiting in
// it are dropped (counted) and the client is sent the whole current state instead, which supersedes
// every update it missed. No sockets here: the daemon's HTTP threads pop and write.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace whiskeye::viewer {

using Update = std::shared_ptr<const std::string>;

class ClientQueue {
 public:
  ClientQueue(uint64_t id, std::size_t capacity) : id_(id), capacity_(capacity) {}
  // Queues an update. When the queue already holds `capacity` updates they are all dropped (counted
  // in dropped()) and the client is marked for a resync; returns false then.
  bool push(Update update);
  enum class Next {
    kUpdate,   // `out` is the next update
    kResync,   // send the whole current state (a new client, or one that fell behind)
    kTimeout,  // nothing within the timeout (the caller may send a keep-alive)
    kClosed,   // the daemon is stopping
  };
  Next pop(Update& out, std::chrono::milliseconds timeout);
  void close();
  uint64_t id() const { return id_; }
  int64_t dropped() const;
  int64_t sent() const;
  int64_t resyncs() const;

 private:
  const uint64_t id_;
  const std::size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Update> queue_;
  bool resync_ = true;  // a new client starts with the whole state
  bool closed_ = false;
  int64_t dropped_ = 0;
  int64_t sent_ = 0;     // updates and resyncs handed out
  int64_t resyncs_ = 0;  // resyncs after falling behind (the first one not counted)
};

class ClientHub {
 public:
  ClientHub(std::size_t max_clients, std::size_t queue_capacity);
  // A new client's queue, or null when max_clients are connected (counted in refused).
  std::shared_ptr<ClientQueue> join();
  void leave(const std::shared_ptr<ClientQueue>& client);
  // Queues the update for every client.
  void broadcast(const Update& update);
  std::size_t clients() const;
  // Wakes every client's writer with kClosed (the daemon is stopping).
  void close_all();

  struct ClientStats {
    uint64_t id;
    int64_t sent, dropped, resyncs;
  };
  struct Stats {
    std::size_t clients = 0;
    std::size_t max_clients = 0;
    std::size_t queue_capacity = 0;
    int64_t joined = 0;
    int64_t refused = 0;
    int64_t broadcasts = 0;
    int64_t dropped = 0;  // over every client, those gone included
    std::vector<ClientStats> per_client;
  };
  Stats stats() const;

 private:
  const std::size_t max_clients_;
  const std::size_t queue_capacity_;
  mutable std::mutex mutex_;
  std::vector<std::shared_ptr<ClientQueue>> clients_;
  uint64_t next_id_ = 1;
  int64_t joined_ = 0;
  int64_t refused_ = 0;
  int64_t broadcasts_ = 0;
  int64_t dropped_by_gone_ = 0;
  bool closed_ = false;
};

}  // namespace whiskeye::viewer
