/* ------------------------------------------------------------------ mesh input */

/* Geometry as it is read, before it becomes an adaslice_mesh. */
typedef struct adaslice__build {
    const char *text;           /* the input, which is not NUL-terminated */
    const unsigned char *bytes; /* the same input, for binary reads */
    size_t size;
    const char *name;           /* the format, for messages */
    double scale;
    adaslice_allocator a;
    adaslice_error *err;
    float *v;                   /* x, y, z per vertex */
    size_t nv, vcap;
    uint32_t *t;                /* three vertex indices per triangle */
    size_t nt, tcap;
} adaslice__build;

static size_t adaslice__at(const adaslice__build *b, const char *w) { return (size_t)(w - b->text); }

/* Fails with the place in front of the message: "OBJ line 12: ..." for text,
   "PLY byte 96: ..." for binary data. */
static adaslice_result adaslice__bad(adaslice__build *b, adaslice_result code, size_t offset,
                                     size_t line, const char *fmt, ...)
{
    char what[256];
    va_list ap;
    va_start(ap, fmt);
    adaslice__vformat(what, sizeof what, fmt, ap);
    va_end(ap);
    if (line) return adaslice__fail(b->err, code, offset, line, "%s line %zu: %s", b->name, line, what);
    return adaslice__fail(b->err, code, offset, 0, "%s byte %zu: %s", b->name, offset, what);
}

/* A word of the input, short and printable enough to quote in a one-line message. */
static const char *adaslice__quote(char q[48], const char *w, size_t n)
{
    size_t i, k = n < 40 ? n : 40;
    for (i = 0; i < k; i++) q[i] = (w[i] >= 32 && w[i] < 127) ? w[i] : '?';
    if (n > k) memcpy(q + k, "...", 4);
    else q[k] = 0;
    return q;
}

/* An integral double as exact text: %g keeps only six digits, too few for an index. */
static const char *adaslice__int_text(char buf[24], double v)
{
    adaslice__out o;
    o.buf = buf; o.cap = 24; o.len = 0;
    if (v < 0) { adaslice__putc(&o, '-'); v = -v; }
    adaslice__putu(&o, (unsigned long long)v);
    buf[o.len] = 0;
    return buf;
}

/* Room for `need` items, at least twice the old capacity so that appending stays
   linear; NULL when out of memory (then `old` is still valid). */
static void *adaslice__grow(const adaslice_allocator *a, void *old, size_t used, size_t *cap,
                            size_t need, size_t item)
{
    size_t n = *cap < SIZE_MAX / 2 ? 2 * *cap : need;
    void *p;
    if (n < need) n = need;
    if (n < 64) n = 64;
    p = adaslice__alloc(a, n, item);
    if (!p) return NULL;
    if (used) memcpy(p, old, used * item);
    adaslice__free(a, old);
    *cap = n;
    return p;
}

static adaslice_result adaslice__reserve(adaslice__build *b, size_t vertices, size_t triangles)
{
    void *p;
    if (vertices > b->vcap) {
        p = adaslice__grow(&b->a, b->v, b->nv, &b->vcap, vertices, 3 * sizeof(float));
        if (!p) return adaslice__fail(b->err, ADASLICE_ERR_NOMEM, 0, 0, "%s: out of memory", b->name);
        b->v = ADASLICE__CAST(float *, p);
    }
    if (triangles > b->tcap) {
        p = adaslice__grow(&b->a, b->t, b->nt, &b->tcap, triangles, 3 * sizeof(uint32_t));
        if (!p) return adaslice__fail(b->err, ADASLICE_ERR_NOMEM, 0, 0, "%s: out of memory", b->name);
        b->t = ADASLICE__CAST(uint32_t *, p);
    }
    return ADASLICE_OK;
}

/* Scales one coordinate; NaN or infinity, in the file or after scaling, is an error (§1). */
static adaslice_result adaslice__coord(adaslice__build *b, double v, size_t offset, size_t line, float *out)
{
    double s = v * b->scale;
    if (!(fabs(v) <= DBL_MAX))
        return adaslice__bad(b, ADASLICE_ERR_NONFINITE, offset, line, "coordinate %g is not finite", v);
    if (!(fabs(s) <= FLT_MAX))
        return adaslice__bad(b, ADASLICE_ERR_NONFINITE, offset, line,
                             "coordinate %g scaled by %g is not finite as a float", v, b->scale);
    *out = (float)s;
    return ADASLICE_OK;
}

static adaslice_result adaslice__vertex(adaslice__build *b, const float xyz[3])
{
    adaslice_result r;
    if (b->nv == UINT32_MAX)
        return adaslice__fail(b->err, ADASLICE_ERR_OVERFLOW, 0, 0,
                              "%s: more than 4294967295 vertices do not fit 32-bit indices", b->name);
    if (b->nv == b->vcap && (r = adaslice__reserve(b, b->nv + 1, 0))) return r;
    memcpy(b->v + 3 * b->nv++, xyz, 3 * sizeof(float));
    return ADASLICE_OK;
}

/* The caller has checked the indices against the vertex count. */
static adaslice_result adaslice__triangle(adaslice__build *b, uint32_t i, uint32_t j, uint32_t k)
{
    uint32_t *t;
    adaslice_result r;
    if (b->nt == b->tcap && (r = adaslice__reserve(b, 0, b->nt + 1))) return r;
    t = b->t + 3 * b->nt++;
    t[0] = i; t[1] = j; t[2] = k;
    return ADASLICE_OK;
}

/* Exactly zero area, in double from the stored floats: repeated corners included. */
static int adaslice__zero_area(const float *v, const uint32_t *t)
{
    const float *a = v + 3 * (size_t)t[0], *p = v + 3 * (size_t)t[1], *q = v + 3 * (size_t)t[2];
    double ux = (double)p[0] - a[0], uy = (double)p[1] - a[1], uz = (double)p[2] - a[2];
    double wx = (double)q[0] - a[0], wy = (double)q[1] - a[1], wz = (double)q[2] - a[2];
    return uy * wz - uz * wy == 0 && uz * wx - ux * wz == 0 && ux * wy - uy * wx == 0;
}

/* Drops zero-area triangles, since no later stage can give them a normal, and hands
   the arrays over to the mesh. The vertices of dropped triangles stay. */
static adaslice_result adaslice__finish(adaslice__build *b, adaslice_mesh *mesh)
{
    size_t i, kept = 0;
    for (i = 0; i < b->nt; i++) {
        const uint32_t *t = b->t + 3 * i;
        uint32_t *to = b->t + 3 * kept;
        if (adaslice__zero_area(b->v, t)) continue;
        to[0] = t[0]; to[1] = t[1]; to[2] = t[2];
        kept++;
    }
    if (!kept && b->nt)
        return adaslice__fail(b->err, ADASLICE_ERR_EMPTY, 0, 0, "%s: all %zu triangles have zero area",
                              b->name, b->nt);
    if (!kept) return adaslice__fail(b->err, ADASLICE_ERR_EMPTY, 0, 0, "%s: no triangles", b->name);
    mesh->vertex_count = b->nv;
    mesh->vertices = b->v;
    mesh->triangle_count = kept;
    mesh->triangles = b->t;
    mesh->degenerate_dropped = b->nt - kept;
    mesh->allocator = b->a;
    b->v = NULL;
    b->t = NULL;
    return ADASLICE_OK;
}

/* ---------------------------------------------------------------- text input */

typedef struct adaslice__text {
    const char *p, *end;
    size_t line; /* 1-based line of p */
} adaslice__text;

static adaslice__text adaslice__text_at(const adaslice__build *b)
{
    adaslice__text t;
    t.p = b->text;
    t.end = b->text + b->size;
    t.line = 1;
    return t;
}

static int adaslice__blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/* The next whitespace-separated word and its length; 0 at the end of the data, or
   of the line unless `cross` lets it read on past newlines. */
static size_t adaslice__word(adaslice__text *t, int cross, const char **w)
{
    const char *p = t->p;
    for (; p < t->end; p++) {
        if (*p == '\n') {
            if (!cross) break;
            t->line++;
        } else if (!adaslice__blank(*p)) break;
    }
    *w = p;
    while (p < t->end && *p != '\n' && !adaslice__blank(*p)) p++;
    t->p = p;
    return (size_t)(p - *w);
}

static void adaslice__skip_line(adaslice__text *t)
{
    while (t->p < t->end && *t->p != '\n') t->p++;
    if (t->p < t->end) { t->p++; t->line++; }
}

/* Case-insensitive comparison with a lowercase keyword. */
static int adaslice__is(const char *w, size_t n, const char *kw)
{
    size_t i;
    for (i = 0; i < n; i++) {
        char c = w[i];
        if (c >= 'A' && c <= 'Z') c = (char)(c - 'A' + 'a');
        if (!kw[i] || c != kw[i]) return 0;
    }
    return kw[n] == 0;
}

/* An optionally signed decimal integer at the front of w[0..n); returns the characters
   read, 0 if there is none. Magnitudes saturate at 2^53: beyond any valid count or
   index, and still exact as a double. */
static size_t adaslice__integer(const char *w, size_t n, long long *out)
{
    size_t i = n && (w[0] == '-' || w[0] == '+'), start = i;
    long long v = 0;
    for (; i < n && w[i] >= '0' && w[i] <= '9'; i++) {
        v = 10 * v + (w[i] - '0');
        if (v > (1LL << 53)) v = 1LL << 53;
    }
    if (i == start) return 0;
    *out = w[0] == '-' ? -v : v;
    return i;
}

/* strtod on a NUL-terminated copy, because the input has no terminator; the whole
   word must be the number. */
static adaslice_result adaslice__number(adaslice__build *b, const char *w, size_t n, size_t line, double *out)
{
    char buf[64], *end, q[48];
    *out = 0;
    if (n < sizeof buf) {
        memcpy(buf, w, n);
        buf[n] = 0;
        *out = strtod(buf, &end);
        if (n && end == buf + n) return ADASLICE_OK;
    }
    return adaslice__bad(b, ADASLICE_ERR_NUMBER, adaslice__at(b, w), line, "'%s' is not a number",
                         adaslice__quote(q, w, n));
}

/* `want` is quoted in the message: pass "facet' or 'endsolid" for two choices. */
static adaslice_result adaslice__unexpected(adaslice__build *b, const adaslice__text *t, const char *w,
                                            size_t n, const char *want)
{
    char q[48];
    if (!n) return adaslice__bad(b, ADASLICE_ERR_TRUNCATED, b->size, t->line,
                                 "the data ends where '%s' was expected", want);
    return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), t->line, "expected '%s', found '%s'",
                         want, adaslice__quote(q, w, n));
}

static adaslice_result adaslice__expect(adaslice__build *b, adaslice__text *t, const char *keyword)
{
    const char *w;
    size_t n = adaslice__word(t, 1, &w);
    return adaslice__is(w, n, keyword) ? ADASLICE_OK : adaslice__unexpected(b, t, w, n, keyword);
}

static adaslice_result adaslice__read_coord(adaslice__build *b, adaslice__text *t, int cross, float *out)
{
    const char *w;
    size_t n = adaslice__word(t, cross, &w);
    double v;
    adaslice_result r;
    if (!n) return adaslice__bad(b, t->p < t->end ? ADASLICE_ERR_FORMAT : ADASLICE_ERR_TRUNCATED,
                                 adaslice__at(b, w), t->line, "the %s ends where a coordinate was expected",
                                 t->p < t->end ? "line" : "data");
    if ((r = adaslice__number(b, w, n, t->line, &v))) return r;
    return adaslice__coord(b, v, adaslice__at(b, w), t->line, out);
}

/* --------------------------------------------------------------- binary data */

enum { ADASLICE__I8 = 1, ADASLICE__U8, ADASLICE__I16, ADASLICE__U16, ADASLICE__I32, ADASLICE__U32,
       ADASLICE__F32, ADASLICE__F64 };
static const unsigned char adaslice__type_size[9] = {0, 1, 1, 2, 2, 4, 4, 4, 8};

/* One value of a PLY scalar type (binary STL uses U32 and F32), assembled byte by
   byte so that the host's byte order and alignment do not matter. */
static double adaslice__scalar(const unsigned char *p, int type, int big_endian)
{
    unsigned n = adaslice__type_size[type], i;
    uint64_t u = 0;
    for (i = 0; i < n; i++) u |= (uint64_t)p[big_endian ? n - 1 - i : i] << (8 * i);
    if (type == ADASLICE__F32) {
        uint32_t bits = (uint32_t)u;
        float f;
        memcpy(&f, &bits, 4);
        return f;
    }
    if (type == ADASLICE__F64) {
        double d;
        memcpy(&d, &u, 8);
        return d;
    }
    if (type % 2 && u >> (8 * n - 1)) return (double)u - ldexp(1.0, (int)(8 * n)); /* signed */
    return (double)u;
}

/* ----------------------------------------------------------------------- STL */

static adaslice_result adaslice__stl_binary(adaslice__build *b)
{
    size_t count, i, at;
    float xyz[3];
    int corner, k;
    adaslice_result r;
    if (b->size < 84)
        return adaslice__bad(b, ADASLICE_ERR_TRUNCATED, b->size, 0,
                             "the data ends inside the 84-byte header and triangle count");
    count = (size_t)adaslice__scalar(b->bytes + 80, ADASLICE__U32, 0);
    /* a wrong count and a cut-off file look alike, so both are a count mismatch */
    if ((b->size - 84) % 50 || (b->size - 84) / 50 != count)
        return adaslice__fail(b->err, ADASLICE_ERR_COUNT, 80, 0,
                              "binary STL: header says %zu triangles (%zu bytes) but the data is %zu bytes",
                              count, 84 + 50 * count, b->size);
    if ((r = adaslice__reserve(b, 3 * count, count))) return r;
    for (i = 0; i < count; i++) {
        for (corner = 0; corner < 3; corner++) { /* the 12-byte normal is ignored: often wrong */
            for (k = 0; k < 3; k++) {
                at = 84 + 50 * i + 12 + 12 * (size_t)corner + 4 * (size_t)k;
                r = adaslice__coord(b, adaslice__scalar(b->bytes + at, ADASLICE__F32, 0), at, 0, &xyz[k]);
                if (r) return r;
            }
            if ((r = adaslice__vertex(b, xyz))) return r;
        }
        r = adaslice__triangle(b, (uint32_t)(b->nv - 3), (uint32_t)(b->nv - 2), (uint32_t)(b->nv - 1));
        if (r) return r;
    }
    return ADASLICE_OK;
}

/* facet normal n n n / outer loop / vertex x y z (three or more) / endloop / endfacet */
static adaslice_result adaslice__stl_facet(adaslice__build *b, adaslice__text *t)
{
    size_t n, corners = 0, first = b->nv;
    const char *w;
    float xyz[3];
    int k;
    adaslice_result r;
    if ((r = adaslice__expect(b, t, "normal"))) return r;
    for (k = 0; k < 3; k++) /* the stored normal is ignored: often wrong */
        if (!(n = adaslice__word(t, 1, &w))) return adaslice__unexpected(b, t, w, n, "normal component");
    if ((r = adaslice__expect(b, t, "outer")) || (r = adaslice__expect(b, t, "loop"))) return r;
    while (n = adaslice__word(t, 1, &w), adaslice__is(w, n, "vertex")) {
        for (k = 0; k < 3; k++)
            if ((r = adaslice__read_coord(b, t, 1, &xyz[k]))) return r;
        if ((r = adaslice__vertex(b, xyz))) return r;
        if (++corners >= 3 && (r = adaslice__triangle(b, (uint32_t)first, (uint32_t)(b->nv - 2),
                                                      (uint32_t)(b->nv - 1))))
            return r;
    }
    if (!adaslice__is(w, n, "endloop")) return adaslice__unexpected(b, t, w, n, "vertex' or 'endloop");
    if (corners < 3)
        return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), t->line,
                             "a facet needs at least 3 vertices, this one has %zu", corners);
    return adaslice__expect(b, t, "endfacet");
}

/* One or more "solid name ... endsolid name" blocks. */
static adaslice_result adaslice__stl_ascii(adaslice__build *b)
{
    adaslice__text t = adaslice__text_at(b);
    const char *w;
    size_t n = adaslice__word(&t, 1, &w);
    adaslice_result r;
    do {
        if (!adaslice__is(w, n, "solid")) return adaslice__unexpected(b, &t, w, n, "solid");
        adaslice__skip_line(&t);
        while (n = adaslice__word(&t, 1, &w), !adaslice__is(w, n, "endsolid")) {
            if (!adaslice__is(w, n, "facet")) return adaslice__unexpected(b, &t, w, n, "facet' or 'endsolid");
            if ((r = adaslice__stl_facet(b, &t))) return r;
        }
        adaslice__skip_line(&t);
    } while ((n = adaslice__word(&t, 1, &w)) != 0);
    return ADASLICE_OK;
}

/* ----------------------------------------------------------------------- OBJ */

/* "7", "7/1", "7/1/3", "7//3" or relative "-1": the vertex part, as a 0-based index
   into the vertices read so far. */
static adaslice_result adaslice__obj_index(adaslice__build *b, const char *w, size_t n, size_t line, uint32_t *out)
{
    long long i, k;
    size_t used = adaslice__integer(w, n, &i);
    char q[48];
    if (!used || (used < n && w[used] != '/'))
        return adaslice__bad(b, ADASLICE_ERR_NUMBER, adaslice__at(b, w), line, "'%s' is not a vertex index",
                             adaslice__quote(q, w, n));
    if (i == 0)
        return adaslice__bad(b, ADASLICE_ERR_INDEX, adaslice__at(b, w), line,
                             "vertex index 0 is invalid (OBJ counts from 1)");
    k = i < 0 ? (long long)b->nv + i : i - 1;
    if (k < 0 || k >= (long long)b->nv)
        return adaslice__bad(b, ADASLICE_ERR_INDEX, adaslice__at(b, w), line,
                             "vertex index %s is out of range (%zu vertices so far)",
                             adaslice__quote(q, w, used), b->nv);
    *out = (uint32_t)k;
    return ADASLICE_OK;
}

/* The corners after "f", fan-triangulated. */
static adaslice_result adaslice__obj_face(adaslice__build *b, adaslice__text *t, const char *keyword)
{
    uint32_t first = 0, prev = 0, cur = 0;
    size_t corners = 0, n;
    const char *w;
    adaslice_result r;
    while ((n = adaslice__word(t, 0, &w)) && w[0] != '#') {
        if ((r = adaslice__obj_index(b, w, n, t->line, &cur))) return r;
        if (corners == 0) first = cur;
        else if (corners >= 2 && (r = adaslice__triangle(b, first, prev, cur))) return r;
        prev = cur;
        corners++;
    }
    if (corners < 3)
        return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, keyword), t->line,
                             "a face needs at least 3 vertices, this one has %zu", corners);
    return ADASLICE_OK;
}

/* Only v and f matter; every other statement (vt, vn, g, usemtl, ...) is skipped. */
static adaslice_result adaslice__obj(adaslice__build *b)
{
    adaslice__text t = adaslice__text_at(b);
    const char *w;
    size_t n;
    float xyz[3];
    int k;
    adaslice_result r;
    while (t.p < t.end) {
        n = adaslice__word(&t, 0, &w);
        if (adaslice__is(w, n, "v")) { /* a w or colours after x y z are ignored */
            for (k = 0; k < 3; k++)
                if ((r = adaslice__read_coord(b, &t, 0, &xyz[k]))) return r;
            if ((r = adaslice__vertex(b, xyz))) return r;
        } else if (adaslice__is(w, n, "f")) {
            if ((r = adaslice__obj_face(b, &t, w))) return r;
        }
        adaslice__skip_line(&t);
    }
    return ADASLICE_OK;
}

/* ----------------------------------------------------------------------- PLY */

enum { ADASLICE__PLY_OTHER, ADASLICE__PLY_X, ADASLICE__PLY_Y, ADASLICE__PLY_Z, ADASLICE__PLY_INDICES };
enum { ADASLICE__PLY_VERTEX = 1, ADASLICE__PLY_FACE, ADASLICE__PLY_STRIPS };

typedef struct adaslice__ply_prop {
    unsigned char type;       /* ADASLICE__I8 ... ADASLICE__F64 */
    unsigned char count_type; /* lists: the type of the length; 0 for scalars */
    unsigned char role;       /* ADASLICE__PLY_X ...; only vertex indices are a list role */
} adaslice__ply_prop;

typedef struct adaslice__ply_elem {
    char name[48];
    size_t count;             /* records */
    size_t at, line;          /* where the header declares it */
    unsigned first, props;    /* its properties in adaslice__ply_reader.props */
    unsigned char kind;       /* ADASLICE__PLY_VERTEX ..., 0 for elements we skip */
} adaslice__ply_elem;

typedef struct adaslice__ply_reader {
    adaslice__build *b;
    adaslice__text t;         /* the header, then ASCII data */
    size_t pos;               /* binary data: offset of the next value */
    size_t at;                /* offset of the value read last */
    int encoding;             /* 0 ASCII, 1 little endian, 2 big endian */
    int has_vertex;
    size_t vertices;          /* records of the vertex element */
    unsigned elem_count, prop_count;
    adaslice__ply_elem elems[32];
    adaslice__ply_prop props[256];
} adaslice__ply_reader;

static size_t adaslice__ply_line(const adaslice__ply_reader *r) { return r->encoding ? 0 : r->t.line; }

static int adaslice__ply_type(const char *w, size_t n)
{
    static const char *const names[16] = {"char", "uchar", "short", "ushort", "int", "uint", "float", "double",
                                           "int8", "uint8", "int16", "uint16", "int32", "uint32", "float32",
                                           "float64"};
    int i;
    for (i = 0; i < 16; i++)
        if (adaslice__is(w, n, names[i])) return i % 8 + 1;
    return 0;
}

static adaslice_result adaslice__ply_element_line(adaslice__ply_reader *r)
{
    adaslice__build *b = r->b;
    adaslice__ply_elem *e;
    const char *w;
    size_t n;
    long long count;
    char q[48];
    if (r->elem_count == 32)
        return adaslice__bad(b, ADASLICE_ERR_UNSUPPORTED, adaslice__at(b, r->t.p), r->t.line,
                             "more than 32 elements");
    e = &r->elems[r->elem_count++];
    e->at = adaslice__at(b, r->t.p);
    e->line = r->t.line;
    e->first = r->prop_count;
    e->props = 0;
    n = adaslice__word(&r->t, 0, &w);
    adaslice__quote(e->name, w, n);
    e->kind = adaslice__is(w, n, "vertex") ? ADASLICE__PLY_VERTEX
            : adaslice__is(w, n, "face") ? ADASLICE__PLY_FACE
            : adaslice__is(w, n, "tristrips") ? ADASLICE__PLY_STRIPS : 0;
    if (e->kind == ADASLICE__PLY_VERTEX && r->has_vertex)
        return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), r->t.line, "a second 'vertex' element");
    n = adaslice__word(&r->t, 0, &w);
    if (!n || adaslice__integer(w, n, &count) != n || count < 0)
        return adaslice__bad(b, ADASLICE_ERR_NUMBER, adaslice__at(b, w), r->t.line,
                             "element count '%s' is not a number", adaslice__quote(q, w, n));
    if (count > UINT32_MAX) /* indices are 32-bit, and no other element gets this big */
        return adaslice__bad(b, ADASLICE_ERR_OVERFLOW, adaslice__at(b, w), r->t.line,
                             "element '%s' count %s exceeds 4294967295", e->name, adaslice__quote(q, w, n));
    e->count = (size_t)count;
    if (e->kind == ADASLICE__PLY_VERTEX) {
        r->has_vertex = 1;
        r->vertices = e->count;
    }
    return ADASLICE_OK;
}

/* "property TYPE NAME" or "property list COUNT_TYPE ITEM_TYPE NAME" */
static adaslice_result adaslice__ply_property_line(adaslice__ply_reader *r)
{
    adaslice__build *b = r->b;
    adaslice__ply_elem *e;
    adaslice__ply_prop *p;
    const char *w;
    size_t n, line = r->t.line;
    int axis;
    char q[48];
    if (!r->elem_count)
        return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, r->t.p), line, "a property before any element");
    if (r->prop_count == 256)
        return adaslice__bad(b, ADASLICE_ERR_UNSUPPORTED, adaslice__at(b, r->t.p), line,
                             "more than 256 properties");
    e = &r->elems[r->elem_count - 1];
    p = &r->props[r->prop_count++];
    e->props++;
    p->count_type = 0;
    n = adaslice__word(&r->t, 0, &w);
    if (adaslice__is(w, n, "list")) {
        n = adaslice__word(&r->t, 0, &w);
        p->count_type = (unsigned char)adaslice__ply_type(w, n);
        if (p->count_type >= ADASLICE__F32)
            return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), line,
                                 "a list length cannot be of type '%s'", adaslice__quote(q, w, n));
        if (p->count_type) n = adaslice__word(&r->t, 0, &w);
    }
    p->type = (unsigned char)adaslice__ply_type(w, n);
    if (!p->type)
        return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), line, "unknown property type '%s'",
                             adaslice__quote(q, w, n));
    n = adaslice__word(&r->t, 0, &w);
    axis = adaslice__is(w, n, "x") ? 1 : adaslice__is(w, n, "y") ? 2 : adaslice__is(w, n, "z") ? 3 : 0;
    p->role = ADASLICE__PLY_OTHER;
    if (axis && e->kind == ADASLICE__PLY_VERTEX) {
        if (p->count_type)
            return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), line, "vertex '%s' is a list",
                                 adaslice__quote(q, w, n));
        p->role = (unsigned char)axis;
    }
    if ((e->kind == ADASLICE__PLY_FACE && adaslice__is(w, n, "vertex_index")) ||
        ((e->kind == ADASLICE__PLY_FACE || e->kind == ADASLICE__PLY_STRIPS) && adaslice__is(w, n, "vertex_indices"))) {
        if (!p->count_type || p->type >= ADASLICE__F32)
            return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), line, "'%s' is not a list of integers",
                                 adaslice__quote(q, w, n));
        p->role = ADASLICE__PLY_INDICES;
    }
    return ADASLICE_OK;
}

static adaslice_result adaslice__ply_header(adaslice__ply_reader *r)
{
    adaslice__build *b = r->b;
    const char *w;
    size_t n = adaslice__word(&r->t, 0, &w);
    unsigned i, k, roles;
    int has_format = 0;
    char q[48];
    adaslice_result res;
    if (!adaslice__is(w, n, "ply")) return adaslice__bad(b, ADASLICE_ERR_FORMAT, 0, 1, "no 'ply' magic");
    for (;;) {
        adaslice__skip_line(&r->t);
        if (r->t.p == r->t.end)
            return adaslice__bad(b, ADASLICE_ERR_TRUNCATED, b->size, r->t.line, "the header has no 'end_header'");
        n = adaslice__word(&r->t, 0, &w);
        res = ADASLICE_OK;
        if (adaslice__is(w, n, "format")) {
            n = adaslice__word(&r->t, 0, &w);
            r->encoding = adaslice__is(w, n, "ascii") ? 0 : adaslice__is(w, n, "binary_little_endian") ? 1
                        : adaslice__is(w, n, "binary_big_endian") ? 2 : -1;
            if (r->encoding < 0)
                return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), r->t.line, "unknown format '%s'",
                                     adaslice__quote(q, w, n));
            n = adaslice__word(&r->t, 0, &w);
            if (!adaslice__is(w, n, "1.0"))
                return adaslice__bad(b, ADASLICE_ERR_UNSUPPORTED, adaslice__at(b, w), r->t.line,
                                     "version '%s' (only 1.0 is read)", adaslice__quote(q, w, n));
            has_format = 1;
        } else if (adaslice__is(w, n, "element")) {
            res = adaslice__ply_element_line(r);
        } else if (adaslice__is(w, n, "property")) {
            res = adaslice__ply_property_line(r);
        } else if (adaslice__is(w, n, "end_header")) {
            break;
        } else if (n && !adaslice__is(w, n, "comment") && !adaslice__is(w, n, "obj_info")) {
            return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), r->t.line,
                                 "unknown header keyword '%s'", adaslice__quote(q, w, n));
        }
        if (res) return res;
    }
    if (!has_format)
        return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), r->t.line, "the header has no 'format' line");
    if (!r->has_vertex)
        return adaslice__bad(b, ADASLICE_ERR_FORMAT, adaslice__at(b, w), r->t.line, "the header has no 'vertex' element");
    for (i = 0; i < r->elem_count; i++) {
        const adaslice__ply_elem *e = &r->elems[i];
        for (roles = 0, k = 0; k < e->props; k++) roles |= 1u << r->props[e->first + k].role;
        if (e->kind == ADASLICE__PLY_VERTEX && (roles & 14u) != 14u)
            return adaslice__bad(b, ADASLICE_ERR_FORMAT, e->at, e->line, "element 'vertex' lacks x, y or z");
        if (e->kind > ADASLICE__PLY_VERTEX && !(roles & 16u))
            return adaslice__bad(b, ADASLICE_ERR_FORMAT, e->at, e->line, "element '%s' has no vertex_indices list",
                                 e->name);
    }
    adaslice__skip_line(&r->t);
    return ADASLICE_OK;
}

/* Reads the next value of `type`. ASCII words are parsed only when `out` is wanted, so
   skipped properties cost no strtod. r->at is where the value began. */
static adaslice_result adaslice__ply_value(adaslice__ply_reader *r, const adaslice__ply_elem *e, size_t record,
                                           int type, double *out)
{
    adaslice__build *b = r->b;
    if (!r->encoding) {
        const char *w;
        size_t n = adaslice__word(&r->t, 1, &w);
        long long i;
        char q[48];
        r->at = adaslice__at(b, w);
        if (!n) goto truncated;
        if (!out) return ADASLICE_OK;
        if (type >= ADASLICE__F32) return adaslice__number(b, w, n, r->t.line, out);
        if (adaslice__integer(w, n, &i) != n)
            return adaslice__bad(b, ADASLICE_ERR_NUMBER, r->at, r->t.line, "'%s' is not an integer",
                                 adaslice__quote(q, w, n));
        *out = (double)i;
        return ADASLICE_OK;
    }
    r->at = r->pos;
    if (b->size - r->pos < adaslice__type_size[type]) goto truncated;
    if (out) *out = adaslice__scalar(b->bytes + r->pos, type, r->encoding == 2);
    r->pos += adaslice__type_size[type];
    return ADASLICE_OK;
truncated:
    return adaslice__bad(b, ADASLICE_ERR_TRUNCATED, r->at, adaslice__ply_line(r),
                         "the data ends inside element '%s' (record %zu of %zu)", e->name, record + 1, e->count);
}

/* A list property: vertex indices become triangles (faces as fans, triangle strips
   with -1 restarts and alternating winding); any other list is walked past. */
static adaslice_result adaslice__ply_list(adaslice__ply_reader *r, const adaslice__ply_elem *e, size_t record,
                                          const adaslice__ply_prop *p)
{
    adaslice__build *b = r->b;
    size_t n, j, at, line, left, run = 0, item = r->encoding ? adaslice__type_size[p->type] : 1;
    uint32_t first = 0, prev = 0, prev2 = 0, cur = 0;
    double v;
    char num[24];
    adaslice_result res;
    if ((res = adaslice__ply_value(r, e, record, p->count_type, &v))) return res;
    at = r->at;
    line = adaslice__ply_line(r);
    if (v < 0) return adaslice__bad(b, ADASLICE_ERR_FORMAT, at, line, "list length %g is negative", v);
    left = r->encoding ? b->size - r->pos : (size_t)(r->t.end - r->t.p);
    if (v > (double)(left / item))
        return adaslice__bad(b, ADASLICE_ERR_TRUNCATED, at, line,
                             "a list of %s entries cannot fit in the %zu bytes left",
                             adaslice__int_text(num, v), left);
    n = (size_t)v;
    for (j = 0; j < n; j++) {
        if ((res = adaslice__ply_value(r, e, record, p->type, p->role ? &v : NULL))) return res;
        if (!p->role) continue;
        if (e->kind == ADASLICE__PLY_STRIPS && v == -1) { run = 0; continue; }
        if (!(v >= 0 && v < (double)r->vertices))
            return adaslice__bad(b, ADASLICE_ERR_INDEX, r->at, adaslice__ply_line(r),
                                 "vertex index %s is out of range (%zu vertices)", adaslice__int_text(num, v),
                                 r->vertices);
        cur = (uint32_t)v;
        if (e->kind == ADASLICE__PLY_FACE) {
            if (j == 0) first = cur;
            else if (j >= 2) res = adaslice__triangle(b, first, prev, cur);
        } else if (run >= 2) { /* odd triangles of a strip run backwards */
            res = run % 2 ? adaslice__triangle(b, prev, prev2, cur) : adaslice__triangle(b, prev2, prev, cur);
        }
        if (res) return res;
        prev2 = prev;
        prev = cur;
        run++;
    }
    if (p->role && e->kind == ADASLICE__PLY_FACE && n < 3)
        return adaslice__bad(b, ADASLICE_ERR_FORMAT, at, line, "a face needs at least 3 vertices, this one has %zu", n);
    return ADASLICE_OK;
}

static adaslice_result adaslice__ply_element(adaslice__ply_reader *r, const adaslice__ply_elem *e)
{
    adaslice__build *b = r->b;
    size_t i, least = 0, left;
    unsigned k;
    adaslice_result res = ADASLICE_OK;
    if (!e->props) return ADASLICE_OK; /* no data, however many records it claims */
    /* Every record takes some bytes (in ASCII a character and a separator per value),
       so a count the data cannot hold is refused before anything is allocated. */
    for (k = 0; k < e->props; k++) {
        const adaslice__ply_prop *p = &r->props[e->first + k];
        least += r->encoding ? adaslice__type_size[p->count_type ? p->count_type : p->type] : 2;
    }
    left = r->encoding ? b->size - r->pos : (size_t)(r->t.end - r->t.p);
    if (e->count > (left + !r->encoding) / least)
        return adaslice__bad(b, ADASLICE_ERR_TRUNCATED, r->encoding ? r->pos : adaslice__at(b, r->t.p),
                             adaslice__ply_line(r),
                             "element '%s' has %zu records of at least %zu bytes, but only %zu bytes remain",
                             e->name, e->count, least, left);
    if (e->kind == ADASLICE__PLY_VERTEX) res = adaslice__reserve(b, e->count, 0);
    else if (e->kind) res = adaslice__reserve(b, 0, b->nt + e->count);
    if (res) return res;
    for (i = 0; i < e->count; i++) {
        float xyz[3] = {0, 0, 0};
        for (k = 0; k < e->props; k++) {
            const adaslice__ply_prop *p = &r->props[e->first + k];
            double v;
            if (p->count_type) {
                res = adaslice__ply_list(r, e, i, p);
            } else if (p->role) {
                res = adaslice__ply_value(r, e, i, p->type, &v);
                if (!res) res = adaslice__coord(b, v, r->at, adaslice__ply_line(r), &xyz[p->role - 1]);
            } else {
                res = adaslice__ply_value(r, e, i, p->type, NULL);
            }
            if (res) return res;
        }
        if (e->kind == ADASLICE__PLY_VERTEX && (res = adaslice__vertex(b, xyz))) return res;
    }
    return ADASLICE_OK;
}

static adaslice_result adaslice__ply(adaslice__build *b)
{
    adaslice__ply_reader r;
    unsigned i;
    adaslice_result res;
    memset(&r, 0, sizeof r);
    r.b = b;
    r.t = adaslice__text_at(b);
    if ((res = adaslice__ply_header(&r))) return res;
    r.pos = adaslice__at(b, r.t.p);
    for (i = 0; i < r.elem_count; i++)
        if ((res = adaslice__ply_element(&r, &r.elems[i]))) return res;
    return ADASLICE_OK;
}

/* ------------------------------------------------------------- the loaders */

static int adaslice__obj_keyword(const char *w, size_t n)
{
    static const char *const keywords[] = {"v", "vt", "vn", "vp", "f", "l", "p", "g", "o", "s", "usemtl", "mtllib"};
    size_t i;
    for (i = 0; i < sizeof keywords / sizeof *keywords; i++)
        if (adaslice__is(w, n, keywords[i])) return 1;
    return 0;
}

/* AUTO: the first rule that matches wins; ADASLICE_FORMAT_AUTO when none does. A
   binary STL header may start with "solid", so the exact size is tested first. */
static adaslice_format adaslice__detect(const adaslice__build *b)
{
    adaslice__text t = adaslice__text_at(b);
    const char *w;
    size_t n;
    if (b->size >= 4 && memcmp(b->text, "ply", 3) == 0 && (b->text[3] == '\n' || adaslice__blank(b->text[3])))
        return ADASLICE_FORMAT_PLY;
    if (b->size >= 84 && (b->size - 84) % 50 == 0 &&
        (double)((b->size - 84) / 50) == adaslice__scalar(b->bytes + 80, ADASLICE__U32, 0))
        return ADASLICE_FORMAT_STL_BINARY;
    n = adaslice__word(&t, 1, &w);
    if (adaslice__is(w, n, "solid")) {
        adaslice__skip_line(&t);
        n = adaslice__word(&t, 1, &w);
        if (adaslice__is(w, n, "facet") || adaslice__is(w, n, "endsolid")) return ADASLICE_FORMAT_STL_ASCII;
    }
    t = adaslice__text_at(b);
    while ((n = adaslice__word(&t, 1, &w)) && w[0] == '#') adaslice__skip_line(&t);
    if (adaslice__obj_keyword(w, n)) return ADASLICE_FORMAT_OBJ;
    return b->size >= 84 ? ADASLICE_FORMAT_STL_BINARY : ADASLICE_FORMAT_AUTO;
}

ADASLICE_DEF adaslice_result adaslice_mesh_load(const void *data, size_t size, const adaslice_load_options *options,
                                                adaslice_mesh *mesh, adaslice_error *error)
{
    adaslice__build b;
    adaslice__text t;
    const char *w;
    adaslice_format format = options ? options->format : ADASLICE_FORMAT_AUTO;
    adaslice_result r;
    adaslice__ok(error);
    if (!mesh) return adaslice__fail(error, ADASLICE_ERR_ARGUMENT, 0, 0, "mesh is NULL");
    memset(mesh, 0, sizeof *mesh);
    if (!data && size) return adaslice__fail(error, ADASLICE_ERR_ARGUMENT, 0, 0, "data is NULL, size %zu", size);
    memset(&b, 0, sizeof b);
    if (!data) data = ""; /* so that no pointer arithmetic touches NULL */
    b.text = ADASLICE__CAST(const char *, data);
    b.bytes = ADASLICE__CAST(const unsigned char *, data);
    b.size = size;
    b.err = error;
    b.scale = options && options->scale != 0 ? options->scale : 1;
    b.a = adaslice__allocator(options ? options->allocator : NULL);
    if (!(b.scale > 0 && b.scale <= DBL_MAX))
        return adaslice__fail(error, ADASLICE_ERR_ARGUMENT, 0, 0, "scale %g is not positive and finite", b.scale);
    if (format == ADASLICE_FORMAT_AUTO) {
        t = adaslice__text_at(&b);
        if (!adaslice__word(&t, 1, &w)) return adaslice__fail(error, ADASLICE_ERR_EMPTY, 0, 0, "the data is empty");
        format = adaslice__detect(&b);
        if (format == ADASLICE_FORMAT_AUTO)
            return adaslice__fail(error, ADASLICE_ERR_FORMAT, 0, 0,
                                  "not a mesh: no 'ply' magic, STL 'solid ... facet' or OBJ statement, "
                                  "and %zu bytes is too short for binary STL", size);
    }
    switch (format) {
    case ADASLICE_FORMAT_STL_BINARY: b.name = "binary STL"; r = adaslice__stl_binary(&b); break;
    case ADASLICE_FORMAT_STL_ASCII: b.name = "ASCII STL"; r = adaslice__stl_ascii(&b); break;
    case ADASLICE_FORMAT_OBJ: b.name = "OBJ"; r = adaslice__obj(&b); break;
    case ADASLICE_FORMAT_PLY: b.name = "PLY"; r = adaslice__ply(&b); break;
    default: return adaslice__fail(error, ADASLICE_ERR_ARGUMENT, 0, 0, "unknown format %d", (int)format);
    }
    if (!r) r = adaslice__finish(&b, mesh);
    if (r) {
        adaslice__free(&b.a, b.v);
        adaslice__free(&b.a, b.t);
        return r;
    }
    mesh->format = format;
    return ADASLICE_OK;
}

ADASLICE_DEF void adaslice_mesh_free(adaslice_mesh *mesh)
{
    if (!mesh) return;
    adaslice__free(&mesh->allocator, mesh->vertices);
    adaslice__free(&mesh->allocator, mesh->triangles);
    memset(mesh, 0, sizeof *mesh);
}

ADASLICE_DEF void adaslice_mesh_bounds(const adaslice_mesh *mesh, double lo[3], double hi[3])
{
    size_t i;
    int k;
    for (k = 0; k < 3; k++) lo[k] = hi[k] = 0;
    for (i = 0; i < 3 * mesh->triangle_count; i++) {
        const float *v = mesh->vertices + 3 * (size_t)mesh->triangles[i];
        for (k = 0; k < 3; k++) {
            if (i == 0 || v[k] < lo[k]) lo[k] = v[k];
            if (i == 0 || v[k] > hi[k]) hi[k] = v[k];
        }
    }
}

#ifndef ADASLICE_NO_STDIO
#include <errno.h>

ADASLICE_DEF adaslice_result adaslice_mesh_load_file(const char *path, const adaslice_load_options *options,
                                                     adaslice_mesh *mesh, adaslice_error *error)
{
    adaslice_allocator a = adaslice__allocator(options ? options->allocator : NULL);
    adaslice_result r;
    void *data = NULL;
    long size = -1;
    FILE *f;
    char why[320];
    if (mesh) memset(mesh, 0, sizeof *mesh);
    if (!path) return adaslice__fail(error, ADASLICE_ERR_ARGUMENT, 0, 0, "path is NULL");
    if (!(f = fopen(path, "rb")))
        return adaslice__fail(error, ADASLICE_ERR_IO, 0, 0, "%s: cannot open: %s", path, strerror(errno));
    if (fseek(f, 0, SEEK_END) == 0) size = ftell(f);
    if (size < 0 || fseek(f, 0, SEEK_SET) != 0) {
        r = adaslice__fail(error, ADASLICE_ERR_IO, 0, 0, "%s: cannot find the size: %s", path, strerror(errno));
    } else if (!(data = adaslice__alloc(&a, (size_t)size, 1))) {
        r = adaslice__fail(error, ADASLICE_ERR_NOMEM, 0, 0, "%s: out of memory for %zu bytes", path, (size_t)size);
    } else if (fread(data, 1, (size_t)size, f) != (size_t)size) {
        r = adaslice__fail(error, ADASLICE_ERR_IO, 0, 0, "%s: cannot read", path);
    } else if ((r = adaslice_mesh_load(data, (size_t)size, options, mesh, error)) && error) {
        memcpy(why, error->message, sizeof why);
        adaslice__fail(error, r, error->offset, error->line, "%s: %s", path, why);
    }
    fclose(f);
    adaslice__free(&a, data);
    return r;
}
#endif
