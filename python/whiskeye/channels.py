"""The stack's LCM channel names and the type each carries (docs/lcm-channels.md).

Generated at build time from common/include/whiskeye/common/channels.h, the one home of the names
(python/assemble.cmake): do not edit; change channels.h. python/whiskeye/channels.py is this file
checked in, so that the source tree's package imports too; test python.LogReaderChannelsAndTypes
fails until it is copied again from build/python/whiskeye/channels.py.
"""

WHISKER_SAMPLE = "WHISKER_SAMPLE"
RCP_STATE = "RCP_STATE"
WHISK_CYCLE = "WHISK_CYCLE"
CAMERA = "CAMERA"
ODOMETRY = "ODOMETRY"
BASE_CMD = "BASE_CMD"
GROUND_TRUTH = "GROUND_TRUTH"
SIM_CONTACT_TRUTH = "SIM_CONTACT_TRUTH"
SIM_FAULT = "SIM_FAULT"
VITA_POSE = "VITA_POSE"
VITA_EVENT = "VITA_EVENT"
VITA_MATCH = "VITA_MATCH"
VITA_MAP = "VITA_MAP"
DRIVER_STATUS = "DRIVER_STATUS"
SLAM_STATUS = "SLAM_STATUS"

# Channel -> name of the LCM type (a module and class of this package) it carries.
TYPES = {
    WHISKER_SAMPLE: "whisker_sample_t",
    RCP_STATE: "rcp_state_t",
    WHISK_CYCLE: "whisk_cycle_t",
    CAMERA: "image_t",
    ODOMETRY: "odometry_t",
    BASE_CMD: "base_cmd_t",
    GROUND_TRUTH: "pose2d_t",
    SIM_CONTACT_TRUTH: "contact_truth_t",
    SIM_FAULT: "sim_fault_t",
    VITA_POSE: "vita_pose_t",
    VITA_EVENT: "vita_event_t",
    VITA_MATCH: "template_match_t",
    VITA_MAP: "vita_map_t",
    DRIVER_STATUS: "driver_status_t",
    SLAM_STATUS: "slam_status_t",
}
