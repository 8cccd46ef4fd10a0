/* Message types, states and error codes of the serial protocol, shared by
   the host tool and the firmware. firmware/PROTOCOL.md is the reference. */
#ifndef FW_PROTOCOL_H
#define FW_PROTOCOL_H

#define FW_PROTOCOL_VERSION 1

/* host -> MCU */
enum {
    FW_MSG_HELLO = 0x01,        /* u8 version -> IDENTIFY; restarts sequence numbers */
    FW_MSG_STATUS = 0x02,       /* -> STATUS */
    FW_MSG_PROFILE = 0x10,      /* u32 bins, u8 bins_min, u8 bins_max, u32 eps_units, u32 bin_nm */
    FW_MSG_PROFILE_DATA = 0x11, /* varints (units << 1 | forced), bin after bin */
    FW_MSG_PLAN_GET = 0x12,     /* u32 first layer (1-based) -> PLAN */
    FW_MSG_PLAN_SET = 0x13,     /* u32 layers, u32 bin_nm: a plan given by the host */
    FW_MSG_PLAN_DATA = 0x14,    /* u8 layer lengths in bins, bottom first */
    FW_MSG_MASK = 0x20,         /* u32 layer, u32 code bytes, u32 CRC-32 of the decoded mask */
    FW_MSG_MASK_DATA = 0x21,    /* the code's next bytes */
    FW_MSG_HOME = 0x30,
    FW_MSG_MOVE = 0x31,         /* i32 z nm, u32 speed um/s (0: the fastest) */
    FW_MSG_EXPOSE = 0x32,       /* u32 ms: the last verified mask, outside a print */
    FW_MSG_PRINT = 0x33,        /* u32 first layer, u32 exposure ms, u32 bottom layers, u32 bottom exposure ms,
                                   u32 peel nm, u32 peel speed um/s, u32 return speed um/s, u32 settle ms */
    FW_MSG_PAUSE = 0x34,
    FW_MSG_RESUME = 0x35,
    FW_MSG_ABORT = 0x36,
    FW_MSG_EXIT = 0x3f          /* emulators: end the program (u8 code) */
};

/* Bit 6 of a host frame's TYPE: the host's resend round (flips at each go-back-N
   resend); a NAK echoes it, so the host can tell a NAK its resend drew from one
   an older copy drew. */
#define FW_ROUND_BIT 0x40u

/* MCU -> host; byte 1 of every frame acknowledges: the next sequence number expected */
enum {
    FW_MSG_ACK = 0x80,          /* u8 0, or a NAK: 1 | the round bit of the frame past the gap */
    FW_MSG_IDENTIFY = 0x81,
    FW_MSG_STATUS_REPLY = 0x82,
    FW_MSG_PLAN = 0x83          /* u32 first layer, u32 layers in all, u32 bin_nm, u8 lengths... */
};

/* STATUS state */
enum { FW_IDLE = 0, FW_HOMING, FW_MOVING, FW_PLANNING, FW_READY, FW_PRINTING, FW_PAUSED, FW_DONE };
/* what a printing layer is doing */
enum { FW_PHASE_MOVE = 0, FW_PHASE_WAIT_MASK, FW_PHASE_SETTLE, FW_PHASE_EXPOSE, FW_PHASE_PEEL };

/* STATUS error: the last command refused, with the sequence number of its frame */
enum {
    FW_ERR_NONE = 0,
    FW_ERR_MESSAGE,      /* unknown type or a payload of the wrong size */
    FW_ERR_PROFILE,      /* a profile header the planner cannot take */
    FW_ERR_PROFILE_DATA, /* more bins than announced, or a bad varint */
    FW_ERR_INFEASIBLE,   /* no plan meets eps with these layer bounds */
    FW_ERR_NO_PLAN,      /* the command needs a plan */
    FW_ERR_MASK_ORDER,   /* not the next mask, or its display buffer is in use */
    FW_ERR_MASK_CODE,    /* the code is malformed or longer than announced */
    FW_ERR_MASK_CRC,     /* the decoded mask's CRC-32 differs: refused, send it again */
    FW_ERR_LIMIT,        /* outside the soft limits */
    FW_ERR_NOT_HOMED,
    FW_ERR_HOME_FAILED,
    FW_ERR_BUSY,         /* not in this state */
    FW_ERR_PLAN_SIZE     /* more bins than max_bins */
};

/* STATUS flags */
#define FW_FLAG_HOMED 1u
#define FW_FLAG_UV 2u
#define FW_FLAG_MOVING 4u
#define FW_FLAG_LINK_LOST 8u
#endif
