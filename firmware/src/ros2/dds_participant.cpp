#include "ros2/dds_participant.hpp"

#include <cstdlib>
#include <memory>

#include "epipole/core/error.hpp"

namespace epipole::firmware::ros2 {

namespace {

// Escapes what XML gives a meaning to (names and addresses come from the board file).
std::string xml_text(const std::string& s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string dds_error(dds_return_t rc) {
  return dds_strretcode(rc);
}

struct QosDelete {
  void operator()(dds_qos_t* q) const { dds_delete_qos(q); }
};

}  // namespace

std::string cyclonedds_config(const DdsNetwork& n) {
  std::string xml = "<CycloneDDS><Domain id=\"any\"><General>";
  if (!n.interfaces.empty()) {
    xml += "<Interfaces>";
    for (const std::string& i : n.interfaces) {
      xml += "<NetworkInterface name=\"" + xml_text(i) + "\"/>";
    }
    xml += "</Interfaces>";
  }
  xml += n.multicast ? "<AllowMulticast>true</AllowMulticast>"
                     : "<AllowMulticast>false</AllowMulticast>";
  xml += "</General><Discovery>";
  if (!n.multicast) {
    xml +=
        "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>32</"
        "MaxAutoParticipantIndex>";
  }
  if (!n.peers.empty()) {
    xml += "<Peers>";
    for (const std::string& p : n.peers) xml += "<Peer address=\"" + xml_text(p) + "\"/>";
    xml += "</Peers>";
  }
  xml += "</Discovery></Domain></CycloneDDS>";
  return xml;
}

DdsParticipant::DdsParticipant(int domain, const std::string& config) {
  const char* uri = std::getenv("CYCLONEDDS_URI");
  by_environment_ = uri != nullptr && *uri != '\0';
  // With CYCLONEDDS_URI set, a domain made with no configuration of its own reads it.
  domain_ = dds_create_domain(static_cast<dds_domainid_t>(domain),
                              by_environment_ ? nullptr : config.c_str());
  if (domain_ < 0) {
    throw Error(cat("ros2: cannot make DDS domain ", domain, ": ", dds_error(domain_),
                    by_environment_ ? cat(" (CYCLONEDDS_URI=", uri, ")") : std::string()));
  }
  participant_ = dds_create_participant(static_cast<dds_domainid_t>(domain), nullptr, nullptr);
  if (participant_ < 0) {
    dds_delete(domain_);
    throw Error(cat("ros2: cannot join DDS domain ", domain, ": ", dds_error(participant_)));
  }
}

DdsParticipant::~DdsParticipant() {
  dds_delete(participant_);
  dds_delete(domain_);
}

dds_entity_t DdsParticipant::writer(const std::string& topic, const dds_topic_descriptor_t* type,
                                    int depth, Durability durability) {
  const dds_entity_t t = dds_create_topic(participant_, type, topic.c_str(), nullptr, nullptr);
  if (t < 0) throw Error(cat("ros2: topic ", topic, ": ", dds_error(t)));
  const std::unique_ptr<dds_qos_t, QosDelete> qos(dds_create_qos());
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, depth);
  dds_qset_durability(qos.get(), durability == Durability::transient_local
                                     ? DDS_DURABILITY_TRANSIENT_LOCAL
                                     : DDS_DURABILITY_VOLATILE);
  const dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(qos.get(), 1, &xcdr1);
  const dds_entity_t w = dds_create_writer(participant_, t, qos.get(), nullptr);
  if (w < 0) throw Error(cat("ros2: writer of ", topic, ": ", dds_error(w)));
  return w;
}

}  // namespace epipole::firmware::ros2
