/* Independent, strict readers for three resin printer job formats, used by the
   tests to check the jobs adaslice writes:
     - ChiTuBox .ctb, versions 2-5 unencrypted layout (magic 0x12FD0086 for
       v2/v3, 0x12FD0106 or 0xFF220810 for v4/v5), little-endian;
     - the encrypted ChiTuBox .ctb (magic 0x12FD0107, v4/v5): the settings
       deciphered, the signature checked;
     - Elegoo .goo "V3.0", big-endian (and Phrozen's .prz, the same file).
   Written from the byte layouts alone (see the notes on resin formats); no
   code from any slicer. CTB layer data is read through the XOR stream of the
   header's EncryptionKey as UVtools documents it in ChituboxFile.cs
   (LayerRleCryptBuffer).  libc, and the encrypted CTB's AES-256 and SHA-256
   from host/codec/aes256.h and host/codec/sha256.h, which test_crypto holds against
   the FIPS and NIST vectors.

   Every offset and size is checked against the buffer; every layer image must
   decode to exactly width*height pixels; on any problem the reader returns -1
   and job->error says what is wrong and at which byte offset of the file. */
#ifndef ADASLICE_JOB_READERS_H
#define ADASLICE_JOB_READERS_H
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

enum { JR_CTB = 1, JR_GOO = 2, JR_CTB_ENCRYPTED = 3 };

/* Flags for the _ex readers. */
enum {
    JR_SKIP_IMAGES = 1,     /* decode and check every layer image, keep none
                               (layers[i].image stays NULL): for full-size jobs */
    JR_SKIP_PREVIEWS = 2    /* do not decode the previews */
};

typedef struct jr_layer {
    /* As stored in the file (float fields widened to double).  Units: mm,
       mm/min, s.  CTB: z/exposure/light_off from the 36-byte layer table, the
       rest from the 84-byte LayerDefEx (v3+; 0 for v2).  CTB stores no
       first-stage retract distance: retract_mm is 0 for CTB.  CTB v4 stores
       lift_mm as the total of both lift stages. */
    double z_mm, exposure_s, light_off_s, lift_mm, lift_speed, retract_mm, retract_speed;
    double lift2_mm, lift2_speed, retract2_mm, retract2_speed;
    double wait_before_cure_s;  /* GOO WaitTimeBeforeCure; CTB RestTimeAfterRetract */
    double wait_after_cure_s;   /* GOO WaitTimeAfterCure;  CTB RestTimeBeforeLift */
    double wait_after_lift_s;   /* GOO WaitTimeAfterLift;  CTB RestTimeAfterLift */
    double pwm;                 /* light PWM 0-255 (CTB: float in LayerDefEx; GOO: u16) */
    int pause;                  /* GOO pause flag; CTB 0 */
    unsigned long long data_offset; /* file offset of the encoded image (GOO: of the 0x55) */
    unsigned long long data_size;   /* its size in bytes (GOO: DataLength) */
    unsigned checksum;          /* GOO: the stored (verified) checksum byte */
    unsigned long long diff_chunks; /* GOO: chunks of type 10, a difference from
                                   the pixel before (a .prz must have none) */
    unsigned char *image;       /* width*height bytes, 8-bit grey, rows in file
                                   order; NULL with JR_SKIP_IMAGES */
} jr_layer;

typedef struct jr_job {
    int format;                 /* JR_CTB or JR_GOO */
    unsigned version;           /* CTB version; GOO 3 */
    unsigned magic;             /* CTB magic (GOO 0) */
    int width, height;          /* pixels */
    double bed_mm[3], layer_height_mm, exposure_s, bottom_exposure_s, light_off_s;
    double total_height_mm;     /* CTB header TotalHeight; GOO 0 */
    unsigned bottom_layers, layer_count;
    unsigned print_time;        /* as stored (s by UVtools) */
    int per_layer_settings;     /* CTB SlicerInfo PerLayerSettings != 0; GOO advance mode */
    unsigned per_layer_raw;     /* the stored byte: CTB SlicerInfo+39, GOO 195445 */
    int anti_alias;             /* CTB SlicerInfo AntiAliasLevel (header's if no
                                   SlicerInfo); GOO header AntiAliasingLevel */
    unsigned ctb_aa_flag;       /* CTB SlicerInfo+36 (7 no AA, 0x0F AA) */
    unsigned ctb_encryption_key;/* CTB header+100 (0 = data in clear) */
    unsigned ctb_software_version;      /* CTB SlicerInfo+48 */
    unsigned ctb_transition_layers;     /* CTB SlicerInfo+60, GOO 195475 */
    unsigned ctb_v4_last_layer_index;   /* CTB v4+: PrintParametersV4+52 */
    unsigned ctb_v4_disclaimer_length;  /* CTB v4+: PrintParametersV4+76 */
    int goo_delay_mode;         /* GOO 195340: 0 light-off delay, 1 wait time */
    int goo_grey_scale_level;   /* GOO 195474 */
    int mirror;                 /* CTB ProjectorType; GOO MirrorX | MirrorY<<1 */
    char machine_name[64];      /* NUL-terminated, cut at 63 bytes */
    int preview_w[2], preview_h[2];  /* [0] small, [1] large; 0 if absent */
    unsigned char *preview_rgb[2];   /* decoded previews, 3 bytes (R,G,B) per pixel */
    jr_layer *layers;           /* layer_count entries */
    char error[256];            /* why reading failed: what, at which byte offset */
} jr_job;

/* 0 ok, else -1 and job->error.  job is overwritten (no need to clear it
   first); on failure nothing stays allocated.  Call jr_free after success. */
int jr_read_ctb(const unsigned char *data, size_t size, jr_job *job);
/* GOO: verifies each layer's checksum, the 0x55 magic, the 0D 0A delimiters,
   the ending string. */
int jr_read_goo(const unsigned char *data, size_t size, jr_job *job);
/* The encrypted CTB: the settings (deciphered) fill the header fields as
   for jr_read_ctb (ctb_encryption_key: the LayerXorKey; ctb_v4_*: the
   settings' LastLayerIndex and DisclaimerSize), each 88-byte LayerDef the
   layer's; fails unless the signature is the enciphered SHA-256 of the
   settings' checksum. */
int jr_read_ctb_encrypted(const unsigned char *data, size_t size, jr_job *job);
int jr_read_ctb_encrypted_ex(const unsigned char *data, size_t size, jr_job *job, unsigned flags);
/* The encrypted CTB's 288-byte settings block deciphered into out; 0, or -1
   when the header does not place 288 bytes inside the file. */
int jr_ctb_encrypted_settings(const unsigned char *data, size_t size, unsigned char out[288]);
/* Same with JR_* flags. */
int jr_read_ctb_ex(const unsigned char *data, size_t size, jr_job *job, unsigned flags);
int jr_read_goo_ex(const unsigned char *data, size_t size, jr_job *job, unsigned flags);
/* Frees what a reader allocated; safe on a zeroed or failed job. */
void jr_free(jr_job *job);

/* The grey value a CTB file can hold for an 8-bit source value v (7 bits are
   stored, decoded as (v>>1)<<1|1 except 0): what to compare decoded CTB
   images against. */
unsigned char jr_ctb_grey(unsigned char v);

/* CTB layer n bytes of layer `layer` (from 0) in clear: the XOR stream of
   the header's EncryptionKey (UVtools' published scheme; key 0: a copy). */
void jr_ctb_decrypt(unsigned key, unsigned layer, const unsigned char *in, size_t n, unsigned char *out);

#ifdef __cplusplus
}
#endif
#endif
