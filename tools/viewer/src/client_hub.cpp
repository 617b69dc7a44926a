// Bounded clients with bounded queues (client_hub.h).
#include "whiskeye/viewer/client_hub.h"

#include <algorithm>

namespace whiskeye::viewer {

bool ClientQueue::push(Update update) {
  {
    std::lock_guard lock(mutex_);
    if (closed_) return true;
    if (queue_.size() >= capacity_) {
      // The whole state will follow: nothing queued (nor this update) needs to be sent.
      dropped_ += static_cast<int64_t>(queue_.size()) + 1;
      queue_.clear();
      if (!resync_) ++resyncs_;
      resync_ = true;
      cv_.notify_one();
      return false;
    }
    if (resync_) return true;  // the resync, still to be sent, will include it
    queue_.push_back(std::move(update));
  }
  cv_.notify_one();
  return true;
}

ClientQueue::Next ClientQueue::pop(Update& out, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  cv_.wait_for(lock, timeout, [&] { return closed_ || resync_ || !queue_.empty(); });
  if (closed_) return Next::kClosed;
  if (resync_) {
    resync_ = false;
    ++sent_;
    return Next::kResync;
  }
  if (queue_.empty()) return Next::kTimeout;
  out = std::move(queue_.front());
  queue_.pop_front();
  ++sent_;
  return Next::kUpdate;
}

void ClientQueue::close() {
  {
    std::lock_guard lock(mutex_);
    closed_ = true;
  }
  cv_.notify_all();
}

int64_t ClientQueue::dropped() const {
  std::lock_guard lock(mutex_);
  return dropped_;
}

int64_t ClientQueue::sent() const {
  std::lock_guard lock(mutex_);
  return sent_;
}

int64_t ClientQueue::resyncs() const {
  std::lock_guard lock(mutex_);
  return resyncs_;
}

ClientHub::ClientHub(std::size_t max_clients, std::size_t queue_capacity)
    : max_clients_(max_clients), queue_capacity_(std::max<std::size_t>(queue_capacity, 1)) {}

std::shared_ptr<ClientQueue> ClientHub::join() {
  std::lock_guard lock(mutex_);
  if (closed_ || clients_.size() >= max_clients_) {
    ++refused_;
    return nullptr;
  }
  auto client = std::make_shared<ClientQueue>(next_id_++, queue_capacity_);
  clients_.push_back(client);
  ++joined_;
  return client;
}

void ClientHub::leave(const std::shared_ptr<ClientQueue>& client) {
  std::lock_guard lock(mutex_);
  const auto it = std::find(clients_.begin(), clients_.end(), client);
  if (it == clients_.end()) return;
  dropped_by_gone_ += client->dropped();
  clients_.erase(it);
}

void ClientHub::broadcast(const Update& update) {
  std::lock_guard lock(mutex_);
  ++broadcasts_;
  for (const auto& c : clients_) c->push(update);
}

std::size_t ClientHub::clients() const {
  std::lock_guard lock(mutex_);
  return clients_.size();
}

void ClientHub::close_all() {
  std::lock_guard lock(mutex_);
  closed_ = true;
  for (const auto& c : clients_) c->close();
}

ClientHub::Stats ClientHub::stats() const {
  std::lock_guard lock(mutex_);
  Stats s;
  s.clients = clients_.size();
  s.max_clients = max_clients_;
  s.queue_capacity = queue_capacity_;
  s.joined = joined_;
  s.refused = refused_;
  s.broadcasts = broadcasts_;
  s.dropped = dropped_by_gone_;
  for (const auto& c : clients_) {
    const ClientStats cs{c->id(), c->sent(), c->dropped(), c->resyncs()};
    s.dropped += cs.dropped;
    s.per_client.push_back(cs);
  }
  return s;
}

}  // namespace whiskeye::viewer
