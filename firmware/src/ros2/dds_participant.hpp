#pragma once

// A DDS participant of the ROS 2 graph (CycloneDDS), and its writers.

#include <dds/dds.h>

#include <string>
#include <vector>

namespace epipole::firmware::ros2 {

// Where DDS may talk: the network interfaces it uses, whether it discovers peers by multicast,
// and the addresses it asks directly (unicast discovery).
struct DdsNetwork {
  std::vector<std::string> interfaces;  // empty: CycloneDDS's own choice
  bool multicast = true;
  std::vector<std::string> peers;
};

// CycloneDDS's configuration for a network (the XML that CYCLONEDDS_URI would name): the
// interfaces; without multicast, participant indexes chosen automatically so that several
// participants on one host each get their own unicast port, and the peers.
std::string cyclonedds_config(const DdsNetwork& network);

enum class Durability { volatile_, transient_local };

class DdsParticipant {
 public:
  // On `domain`, with `config` (cyclonedds_config()), or, when the environment names one
  // (CYCLONEDDS_URI), with that instead, as every CycloneDDS program does. Throws Error.
  DdsParticipant(int domain, const std::string& config);
  ~DdsParticipant();
  DdsParticipant(const DdsParticipant&) = delete;
  DdsParticipant& operator=(const DdsParticipant&) = delete;

  // A reliable keep-last writer of `depth` on `topic` (a DDS topic name, "rt/epipole/depth"),
  // offering XCDR1 only. Throws Error.
  dds_entity_t writer(const std::string& topic, const dds_topic_descriptor_t* type, int depth,
                      Durability durability = Durability::volatile_);
  // Whether the configuration came from CYCLONEDDS_URI.
  bool configured_by_environment() const { return by_environment_; }

 private:
  dds_entity_t domain_ = 0;
  dds_entity_t participant_ = 0;
  bool by_environment_ = false;
};

}  // namespace epipole::firmware::ros2
