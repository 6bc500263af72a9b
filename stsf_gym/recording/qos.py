"""The QoS profile each topic of a log was offered with, as rosbag2 stores it in an MCAP
channel's metadata (``offered_qos_profiles``), so that ``ros2 bag play`` republishes each topic
as a live publisher would: ``/tf_static`` latched (transient-local durability, as tf2's static
broadcaster offers it), every other topic volatile.

The text is rosbag2's YAML list of profiles in its integer encoding (metadata version 8), the
one every rosbag2 release reads (later releases detect it); the policy numbers are
``rmw_qos_profile_t``'s. Like a profile rosbag2 records from a discovered publisher, it names
no history (``unknown``, depth 0) and infinite deadline, lifespan and liveliness lease.
"""

from __future__ import annotations

import yaml

from stsf_gym.recording import topics

#: The metadata key of an MCAP channel that holds the profiles (rosbag2's name).
METADATA_KEY = "offered_qos_profiles"
#: Topics offered transient-local (latched): a late subscriber still gets their last message.
LATCHED = frozenset({topics.TF_STATIC})

# rmw_qos_profile_t policy values (rmw/types.h)
HISTORY_UNKNOWN = 3
RELIABILITY_RELIABLE = 1
DURABILITY_TRANSIENT_LOCAL, DURABILITY_VOLATILE = 1, 2
LIVELINESS_AUTOMATIC = 1
#: RMW_DURATION_INFINITE as rosbag2 writes it.
INFINITE = {"sec": 9223372036, "nsec": 854775807}


def offered_profile(topic: str) -> dict:
    """The QoS profile ``topic`` is offered with, as rosbag2's YAML mapping (integer policies)."""
    latched = topic in LATCHED
    return {
        "history": HISTORY_UNKNOWN,
        "depth": 0,
        "reliability": RELIABILITY_RELIABLE,
        "durability": DURABILITY_TRANSIENT_LOCAL if latched else DURABILITY_VOLATILE,
        "deadline": dict(INFINITE),
        "lifespan": dict(INFINITE),
        "liveliness": LIVELINESS_AUTOMATIC,
        "liveliness_lease_duration": dict(INFINITE),
        "avoid_ros_namespace_conventions": False,
    }


def channel_metadata(topic: str) -> dict[str, str]:
    """The MCAP channel metadata rosbag2 writes for ``topic``: ``offered_qos_profiles``, a YAML
    list of one profile (:func:`offered_profile`)."""
    text = yaml.safe_dump([offered_profile(topic)], default_flow_style=False, sort_keys=False)
    return {METADATA_KEY: text.strip()}
