/* trilux's C shim over Intel Embree 3 and 4: see shim.h for the interface.
 *
 * Everything version-specific lives here, behind TX_EMBREE_MAJOR (set by build.rs) and
 * RTC_GEOMETRY_INSTANCE_ARRAY (Embree 4.3+ built with instance arrays: hits are larger).
 *
 * Embree and the built-in BVH answer every query alike, primitive and t: Embree proposes
 * candidates and trilux's exact routines (through function pointers) decide them. Quads and
 * triangles are handed to Embree slightly enlarged, and a filter on them runs the exact test
 * on each candidate; user geometry (spheres, rings) runs it as its intersection. Embree's own
 * Pluecker test can settle a ray through a shared edge differently from trilux's watertight
 * one: on the course's Cornell box it gave the edge between the ceiling and the one-sided light
 * (seen from behind) to the light, so a camera ray left the closed box through it. A query's
 * best hit so far lives in its context (`TxQuery`), one per ray, found by the ray's id: the
 * nearest accepted hit, and of equally near ones the smallest key -- the BVH's rule. */
#include "shim.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <xmmintrin.h>
#include <pmmintrin.h>

#if TX_EMBREE_MAJOR >= 4
#include <embree4/rtcore.h>
#else
#include <embree3/rtcore.h>
#endif


/* Embree's RTCRayN/RTCHitN accessors are C++ only; these are the same SoA layout for C. */
#define TX_RAYN_F(ray, N, i, k) (((float*)(ray))[(k) * (N) + (i)])
#define TX_HITN_F(hit, N, i, k) (((float*)(hit))[(k) * (N) + (i)])
#define TX_HITN_U(hit, N, i, k) (((unsigned int*)(hit))[(k) * (N) + (i)])
#define TX_RAYN_U(ray, N, i, k) (((const unsigned int*)(ray))[(k) * (N) + (i)])
#define RAY_ORG_X 0
#define RAY_ORG_Y 1
#define RAY_ORG_Z 2
#define RAY_TNEAR 3
#define RAY_DIR_X 4
#define RAY_DIR_Y 5
#define RAY_DIR_Z 6
#define RAY_TFAR 8
#define HIT_NG_X 0
#define HIT_NG_Y 1
#define HIT_NG_Z 2
#define HIT_U 3
#define HIT_V 4
#define HIT_PRIM 5
#define HIT_GEOM 6
#define HIT_INST0 7
#define RAY_ID 10
/* Embree 4.3+ built with instance arrays has instPrimID after the instID levels. */
#define HIT_INST_PRIM0 (HIT_INST0 + RTC_MAX_INSTANCE_LEVEL_COUNT)
#define TX_RAYHITN_RAY(rh, N) ((struct RTCRayN*)(rh))
#define TX_RAYHITN_HIT(rh, N) ((struct RTCHitN*)&((float*)(rh))[12 * (N)])

#define TX_MAX_GEOMETRIES 8

struct TxDevice {
  RTCDevice device;
};

/* A geometry's exact routine, and the key its primitive `prim` has in the tie rule
 * (`key_base | prim`); bounds only for user geometry. */
typedef struct TxExact {
  const void* user;
  TxBoundsFn bounds;
  TxIntersectFn exact;
  unsigned int key_base;
  /* For a group's triangles in place of `exact`: they are decided on the query's own ray. */
  TxInstancedFn instanced;
} TxExact;

struct TxScene {
  RTCScene scene;
  /* Whether Embree's candidates are decided by the exact routines (`--embree-exact`). */
  int exact;
  /* Front normals of one-sided quads and triangles, for the filter of a scene that is not
   * exact (index 0 quads, 1 triangles). */
  float* front_normals[2];
  TxExact geometries[TX_MAX_GEOMETRIES];
  unsigned int n_geometries;
};

/* One ray's query: its range as asked, and the best hit the exact routines accepted so far
 * (key TX_INVALID_ID: none yet, and `t` is the end of the range). */
typedef struct TxBest {
  float near;
  float limit;
  float t;
  float u;
  float v;
  unsigned int key;
  unsigned int geom;
  unsigned int prim;
  unsigned int inst;
  /* The ray as the query asked it: an instanced triangle's filter sees Embree's ray in the
   * group's space, and decides on this one instead (see TxInstancedFn). */
  TxRay ray;
} TxBest;

/* The context of a query: Embree's, extended (as its documentation allows) with the rays'
 * bests, indexed by ray id. Callbacks receive a pointer to `context` and cast it back. */
typedef struct TxQuery {
#if TX_EMBREE_MAJOR >= 4
  struct RTCRayQueryContext context;
#else
  struct RTCIntersectContext context;
#endif
  TxBest* best;
} TxQuery;

/* ---- errors ---------------------------------------------------------------------------- */

static pthread_mutex_t error_lock = PTHREAD_MUTEX_INITIALIZER;
static char error_message[512];

static void record_error(const char* what) {
  pthread_mutex_lock(&error_lock);
  strncpy(error_message, what, sizeof error_message - 1);
  error_message[sizeof error_message - 1] = '\0';
  pthread_mutex_unlock(&error_lock);
}

static void error_callback(void* user, enum RTCError code, const char* str) {
  (void)user;
  char buf[sizeof error_message];
  const char* kind = "unknown error";
  switch (code) {
    case RTC_ERROR_NONE: return;
    case RTC_ERROR_INVALID_ARGUMENT: kind = "invalid argument"; break;
    case RTC_ERROR_INVALID_OPERATION: kind = "invalid operation"; break;
    case RTC_ERROR_OUT_OF_MEMORY: kind = "out of memory"; break;
    case RTC_ERROR_UNSUPPORTED_CPU: kind = "unsupported CPU"; break;
    case RTC_ERROR_CANCELLED: kind = "cancelled"; break;
    default: break;
  }
  snprintf(buf, sizeof buf, "Embree: %s: %s", kind, str ? str : "");
  record_error(buf);
}

size_t tx_last_error(char* buf, size_t len) {
  pthread_mutex_lock(&error_lock);
  size_t n = strlen(error_message);
  if (n > 0 && buf && len > 0) {
    size_t copy = n < len - 1 ? n : len - 1;
    memcpy(buf, error_message, copy);
    buf[copy] = '\0';
  }
  error_message[0] = '\0';
  pthread_mutex_unlock(&error_lock);
  return n;
}

int tx_embree_major(void) { return TX_EMBREE_MAJOR; }

void tx_set_flush_denormals(void) {
  _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
  _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
}

/* ---- device and scene ------------------------------------------------------------------ */

TxDevice* tx_device_new(const char* config) {
  RTCDevice device = rtcNewDevice(config);
  if (!device) {
    char buf[128];
    snprintf(buf, sizeof buf, "Embree: cannot create a device (error code %d)",
             (int)rtcGetDeviceError(NULL));
    record_error(buf);
    return NULL;
  }
  rtcSetDeviceErrorFunction(device, error_callback, NULL);
  TxDevice* d = (TxDevice*)calloc(1, sizeof *d);
  if (!d) {
    rtcReleaseDevice(device);
    record_error("trilux shim: out of memory");
    return NULL;
  }
  d->device = device;
  return d;
}

void tx_device_release(TxDevice* device) {
  if (!device) return;
  rtcReleaseDevice(device->device);
  free(device);
}

TxScene* tx_scene_new(TxDevice* device, int quality, int robust, int exact) {
  RTCScene scene = rtcNewScene(device->device);
  if (!scene) return NULL;
  TxScene* s = (TxScene*)calloc(1, sizeof *s);
  if (!s) {
    rtcReleaseScene(scene);
    record_error("trilux shim: out of memory");
    return NULL;
  }
  s->scene = scene;
  s->exact = exact;
  enum RTCBuildQuality q =
      quality <= 0 ? RTC_BUILD_QUALITY_LOW
                   : (quality == 1 ? RTC_BUILD_QUALITY_MEDIUM : RTC_BUILD_QUALITY_HIGH);
  rtcSetSceneBuildQuality(scene, q);
  rtcSetSceneFlags(scene, robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
  return s;
}

void tx_scene_release(TxScene* scene) {
  if (!scene) return;
  rtcReleaseScene(scene->scene);
  free(scene->front_normals[0]);
  free(scene->front_normals[1]);
  free(scene);
}

static TxRay load_ray(const struct RTCRayN* ray, unsigned int N, unsigned int i) {
  TxRay r;
  r.org[0] = TX_RAYN_F(ray, N, i, RAY_ORG_X);
  r.org[1] = TX_RAYN_F(ray, N, i, RAY_ORG_Y);
  r.org[2] = TX_RAYN_F(ray, N, i, RAY_ORG_Z);
  r.tnear = TX_RAYN_F(ray, N, i, RAY_TNEAR);
  r.dir[0] = TX_RAYN_F(ray, N, i, RAY_DIR_X);
  r.dir[1] = TX_RAYN_F(ray, N, i, RAY_DIR_Y);
  r.dir[2] = TX_RAYN_F(ray, N, i, RAY_DIR_Z);
  r.tfar = TX_RAYN_F(ray, N, i, RAY_TFAR);
  return r;
}

static TxBest* best_of(const void* context, const struct RTCRayN* ray, unsigned int N,
                       unsigned int i) {
  const TxQuery* q = (const TxQuery*)context;
  return &q->best[TX_RAYN_U(ray, N, i, RAY_ID)];
}

/* How far Embree may still propose candidates once `t` is the best: a little beyond it, so
 * that a primitive whose exact t ties with it is proposed although Embree's own t for it may
 * be a few ulps larger; never beyond the query's range. */
static float room(const TxBest* best) {
  float r = best->t + fabsf(best->t) * 1e-5f + 1e-30f;
  return r < best->limit ? r : best->limit;
}

/* The ray a candidate of geometry g is decided on: lane i of Embree's, or for a group's
 * triangle the query's own (Embree's is then in the group's space). */
static TxRay candidate_ray(const TxExact* g, const struct RTCRayN* ray, unsigned int N,
                           unsigned int i, const TxBest* best) {
  return g->instanced ? best->ray : load_ray(ray, N, i);
}

/* Runs geometry g's exact routine on candidate `prim` (of the instance of geometry id `inst`,
 * or TX_INVALID_ID) for ray r, over r's range; writes t, u, v and the key. */
static int run_exact(const TxExact* g, unsigned int inst, unsigned int prim, const TxRay* r,
                     float* t, float* u, float* v, unsigned int* key) {
  if (g->instanced) return g->instanced(g->user, inst, prim, r, t, u, v, key);
  *key = g->key_base | prim;
  return g->exact(g->user, prim, r, t, u, v);
}

/* Runs the exact routine of geometry g on a candidate (primitive prim, in instance inst or
 * TX_INVALID_ID) on ray r and makes it the ray's best if it is hit before `cap`, nearer than
 * the best, or as near with a smaller key. */
static int offer(const TxExact* g, unsigned int geom, unsigned int inst, unsigned int prim,
                 TxRay r, TxBest* best, float cap) {
  r.tnear = best->near;
  /* Up to the best's t inclusive (a tie may win on its key); before any, the range. */
  const float upto = best->key == TX_INVALID_ID ? best->limit : nextafterf(best->t, INFINITY);
  r.tfar = cap < upto ? cap : upto;
  float t, u, v;
  unsigned int key;
  if (!run_exact(g, inst, prim, &r, &t, &u, &v, &key)) return 0;
  if (best->key != TX_INVALID_ID && !(t < best->t || key < best->key)) return 0;
  best->t = t;
  best->u = u;
  best->v = v;
  best->key = key;
  best->geom = geom;
  best->prim = prim;
  best->inst = inst;
  return 1;
}

/* Whether a candidate is hit by the exact routine on ray r within the query's range. */
static int exact_occludes(const TxExact* g, unsigned int inst, unsigned int prim, TxRay r,
                          const TxBest* best) {
  r.tnear = best->near;
  r.tfar = best->limit;
  float t, u, v;
  unsigned int key;
  return run_exact(g, inst, prim, &r, &t, &u, &v, &key);
}

/* The instance a filter's candidate lies in (TX_INVALID_ID outside instances). */
static unsigned int instance_of(const struct RTCFilterFunctionNArguments* args) {
  return args->context->instID[0];
}

/* Embree's candidate hits on quads and triangles, decided by the exact routine. */
static void exact_intersect_filter(const struct RTCFilterFunctionNArguments* args) {
  const TxExact* g = (const TxExact*)args->geometryUserPtr;
  const unsigned int N = args->N;
  for (unsigned int i = 0; i < N; i++) {
    if (args->valid[i] != -1) continue;
    TxBest* best = best_of(args->context, args->ray, N, i);
    const unsigned int geom = TX_HITN_U(args->hit, N, i, HIT_GEOM);
    const unsigned int prim = TX_HITN_U(args->hit, N, i, HIT_PRIM);
    const TxRay r = candidate_ray(g, args->ray, N, i, best);
    /* The ray's tfar is Embree's own t for this candidate here: no bound for the exact t. */
    if (offer(g, geom, instance_of(args), prim, r, best, INFINITY)) {
      TX_RAYN_F(args->ray, N, i, RAY_TFAR) = room(best);
    } else {
      args->valid[i] = 0;
    }
  }
}

static void exact_occluded_filter(const struct RTCFilterFunctionNArguments* args) {
  const TxExact* g = (const TxExact*)args->geometryUserPtr;
  const unsigned int N = args->N;
  for (unsigned int i = 0; i < N; i++) {
    if (args->valid[i] != -1) continue;
    const unsigned int prim = TX_HITN_U(args->hit, N, i, HIT_PRIM);
    const TxBest* best = best_of(args->context, args->ray, N, i);
    const TxRay r = candidate_ray(g, args->ray, N, i, best);
    if (!exact_occludes(g, instance_of(args), prim, r, best)) args->valid[i] = 0;
  }
}

/* The largest coordinate magnitude of n points (3 floats each), at least 1: the scale of the
 * rounding in Embree's test. */
static float magnitude(const float* points, size_t n) {
  float m = 1.0f;
  for (size_t k = 0; k < 3 * n; k++) m = fmaxf(m, fabsf(points[k]));
  return m;
}

/* A polygon (convex, planar) scaled about its centroid so that each edge moves outward by at
 * least `margin`: Embree, testing the larger polygon, then proposes every point the exact
 * test can accept despite its own rounding. Scaling (not moving coordinates one by one, which
 * can turn an edge inward) keeps the edges parallel; a sliver is at most doubled. */
static void enlarge(const float* in, float* out, int corners, float margin) {
  double c[3] = {0.0, 0.0, 0.0};
  for (int k = 0; k < corners; k++)
    for (int a = 0; a < 3; a++) c[a] += in[3 * k + a] / (double)corners;
  /* The centroid's distance to the nearest edge line. */
  double h = INFINITY;
  for (int k = 0; k < corners; k++) {
    const float* p = in + 3 * k;
    const float* q = in + 3 * ((k + 1) % corners);
    double e[3], w[3];
    for (int a = 0; a < 3; a++) {
      e[a] = (double)q[a] - p[a];
      w[a] = c[a] - p[a];
    }
    const double x = e[1] * w[2] - e[2] * w[1];
    const double y = e[2] * w[0] - e[0] * w[2];
    const double z = e[0] * w[1] - e[1] * w[0];
    const double len = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    if (len > 0.0) h = fmin(h, sqrt(x * x + y * y + z * z) / len);
  }
  double scale = h > 0.0 ? (double)margin / h : 1.0;
  scale = fmin(fmax(scale, 1e-4), 1.0);
  for (int k = 0; k < corners; k++)
    for (int a = 0; a < 3; a++)
      out[3 * k + a] = (float)(c[a] + ((double)in[3 * k + a] - c[a]) * (1.0 + scale));
}

/* The margin by which polygons are enlarged, against coordinates of magnitude m: about 80
 * ulps of them, far above the rounding of Embree's test and far below anything visible (the
 * hits themselves are the exact routine's). */
static float margin_for(float m) { return m * 1e-5f; }

/* In a scene that is not exact: rejects hits on the back side of one-sided quads or triangles
 * (the geometry's user data is the array of their front normals). */
static void front_filter(const struct RTCFilterFunctionNArguments* args) {
  const float* normals = (const float*)args->geometryUserPtr;
  const unsigned int N = args->N;
  for (unsigned int i = 0; i < N; i++) {
    if (args->valid[i] != -1) continue;
    const unsigned int prim = TX_HITN_U(args->hit, N, i, HIT_PRIM);
    const float* n = normals + 3 * (size_t)prim;
    const float d = n[0] * TX_RAYN_F(args->ray, N, i, RAY_DIR_X) +
                    n[1] * TX_RAYN_F(args->ray, N, i, RAY_DIR_Y) +
                    n[2] * TX_RAYN_F(args->ray, N, i, RAY_DIR_Z);
    if (d >= 0.0f) args->valid[i] = 0;
  }
}

/* Registers a geometry's exact routine, as its user data; NULL when there are too many. */
static TxExact* add_exact(TxScene* s, const void* user, TxBoundsFn bounds, TxIntersectFn exact,
                          unsigned int key_base) {
  if (s->n_geometries >= TX_MAX_GEOMETRIES) {
    record_error("trilux shim: too many geometries in one scene");
    return NULL;
  }
  TxExact* g = &s->geometries[s->n_geometries++];
  g->user = user;
  g->bounds = bounds;
  g->exact = exact;
  g->key_base = key_base;
  g->instanced = NULL;
  return g;
}

static unsigned int attach(TxScene* s, RTCGeometry geom) {
  rtcCommitGeometry(geom);
  unsigned int id = rtcAttachGeometry(s->scene, geom);
  rtcReleaseGeometry(geom);
  return id;
}

/* Attaches a quad or triangle geometry whose hits the exact routine decides. */
static unsigned int attach_decided(TxScene* s, RTCGeometry geom, const void* user,
                                   TxIntersectFn exact, unsigned int key_base) {
  TxExact* g = add_exact(s, user, NULL, exact, key_base);
  if (!g) {
    rtcReleaseGeometry(geom);
    return TX_INVALID_ID;
  }
  rtcSetGeometryUserData(geom, g);
  rtcSetGeometryIntersectFilterFunction(geom, exact_intersect_filter);
  rtcSetGeometryOccludedFilterFunction(geom, exact_occluded_filter);
  return attach(s, geom);
}

/* Attaches a geometry of a scene that is not exact, its n primitives' backs missed by the
 * filter when front_normals is not NULL (kept in slot `which` of the scene: 0 quads, 1
 * triangles; one geometry of each). */
static unsigned int attach_one_sided(TxScene* s, RTCGeometry geom, const float* front_normals,
                                     unsigned int n, int which) {
  if (!front_normals) return attach(s, geom);
  if (s->front_normals[which]) {
    record_error("trilux shim: only one one-sided geometry of a kind per scene");
    rtcReleaseGeometry(geom);
    return TX_INVALID_ID;
  }
  float* normals = (float*)malloc(3 * sizeof(float) * (size_t)n);
  if (!normals) {
    rtcReleaseGeometry(geom);
    record_error("trilux shim: out of memory");
    return TX_INVALID_ID;
  }
  memcpy(normals, front_normals, 3 * sizeof(float) * (size_t)n);
  s->front_normals[which] = normals;
  rtcSetGeometryUserData(geom, normals);
  rtcSetGeometryIntersectFilterFunction(geom, front_filter);
  rtcSetGeometryOccludedFilterFunction(geom, front_filter);
  return attach(s, geom);
}

unsigned int tx_scene_add_quads(TxScene* s, const float* vertices, unsigned int n,
                                const float* front_normals, const void* user,
                                TxIntersectFn exact, unsigned int key_base) {
  RTCDevice device = rtcGetSceneDevice(s->scene);
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_QUAD);
  rtcReleaseDevice(device); /* rtcGetSceneDevice retained it */
  if (!geom) return TX_INVALID_ID;
  float* vb = (float*)rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                              3 * sizeof(float), 4 * (size_t)n);
  unsigned int* ib = (unsigned int*)rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4, 4 * sizeof(unsigned int), n);
  if (!vb || !ib) {
    rtcReleaseGeometry(geom);
    return TX_INVALID_ID;
  }
  for (unsigned int i = 0; i < 4 * n; i++) ib[i] = i;
  if (s->exact) {
    const float margin = margin_for(magnitude(vertices, 4 * (size_t)n));
    for (size_t q = 0; q < n; q++) enlarge(vertices + 12 * q, vb + 12 * q, 4, margin);
    return attach_decided(s, geom, user, exact, key_base);
  }
  memcpy(vb, vertices, 12 * sizeof(float) * (size_t)n);
  return attach_one_sided(s, geom, front_normals, n, 0);
}

/* A triangle geometry of the mesh, its vertices enlarged one triangle at a time in an exact
 * scene; NULL on failure. */
static RTCGeometry triangle_geometry(TxScene* s, const float* vertices,
                                     const unsigned int* indices, unsigned int n_triangles) {
  RTCDevice device = rtcGetSceneDevice(s->scene);
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcReleaseDevice(device);
  if (!geom) return NULL;
  size_t n_vertices = 0;
  for (size_t i = 0; i < 3 * (size_t)n_triangles; i++)
    if (indices[i] + 1 > n_vertices) n_vertices = indices[i] + 1;
  /* An exact scene enlarges each triangle on its own, so its vertices are not shared. Embree
   * may read 16 bytes at the last vertex: the buffer it allocates itself is padded. */
  const size_t n_buffer = s->exact ? 3 * (size_t)n_triangles : n_vertices;
  float* vb = (float*)rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                              3 * sizeof(float), n_buffer);
  unsigned int* ib = (unsigned int*)rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned int), n_triangles);
  if (!vb || !ib) {
    rtcReleaseGeometry(geom);
    return NULL;
  }
  if (!s->exact) {
    memcpy(vb, vertices, 3 * sizeof(float) * n_vertices);
    memcpy(ib, indices, 3 * sizeof(unsigned int) * (size_t)n_triangles);
    return geom;
  }
  const float margin = margin_for(magnitude(vertices, n_vertices));
  for (size_t t = 0; t < n_triangles; t++) {
    float corners[9];
    for (int k = 0; k < 3; k++)
      memcpy(corners + 3 * k, vertices + 3 * (size_t)indices[3 * t + k], 3 * sizeof(float));
    enlarge(corners, vb + 9 * t, 3, margin);
  }
  for (size_t i = 0; i < 3 * (size_t)n_triangles; i++) ib[i] = (unsigned int)i;
  return geom;
}

unsigned int tx_scene_add_triangles(TxScene* s, const float* vertices,
                                    const unsigned int* indices, unsigned int n_triangles,
                                    const float* front_normals, const void* user,
                                    TxIntersectFn exact, unsigned int key_base) {
  RTCGeometry geom = triangle_geometry(s, vertices, indices, n_triangles);
  if (!geom) return TX_INVALID_ID;
  if (!s->exact) return attach_one_sided(s, geom, front_normals, n_triangles, 1);
  return attach_decided(s, geom, user, exact, key_base);
}

unsigned int tx_scene_add_group_triangles(TxScene* s, const float* vertices,
                                          const unsigned int* indices, unsigned int n_triangles,
                                          const void* user, TxInstancedFn exact) {
  RTCGeometry geom = triangle_geometry(s, vertices, indices, n_triangles);
  if (!geom) return TX_INVALID_ID;
  if (!s->exact) return attach(s, geom);
  TxExact* g = add_exact(s, user, NULL, NULL, 0);
  if (!g) {
    rtcReleaseGeometry(geom);
    return TX_INVALID_ID;
  }
  g->instanced = exact;
  rtcSetGeometryUserData(geom, g);
  rtcSetGeometryIntersectFilterFunction(geom, exact_intersect_filter);
  rtcSetGeometryOccludedFilterFunction(geom, exact_occluded_filter);
  return attach(s, geom);
}

unsigned int tx_scene_add_instance(TxScene* s, const TxScene* group, const float* to_world) {
  RTCDevice device = rtcGetSceneDevice(s->scene);
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
  rtcReleaseDevice(device);
  if (!geom) return TX_INVALID_ID;
  rtcSetGeometryInstancedScene(geom, group->scene);
  rtcSetGeometryTimeStepCount(geom, 1);
  rtcSetGeometryTransform(geom, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, to_world);
  return attach(s, geom);
}

/* ---- user geometry ----------------------------------------------------------------------- */

static void user_bounds(const struct RTCBoundsFunctionArguments* args) {
  const TxExact* u = (const TxExact*)args->geometryUserPtr;
  float lo[3], hi[3];
  u->bounds(u->user, args->primID, lo, hi);
  args->bounds_o->lower_x = lo[0];
  args->bounds_o->lower_y = lo[1];
  args->bounds_o->lower_z = lo[2];
  args->bounds_o->upper_x = hi[0];
  args->bounds_o->upper_y = hi[1];
  args->bounds_o->upper_z = hi[2];
}

static void user_intersect(const struct RTCIntersectFunctionNArguments* args) {
  const TxExact* u = (const TxExact*)args->geometryUserPtr;
  const unsigned int N = args->N;
  struct RTCRayN* ray = TX_RAYHITN_RAY(args->rayhit, N);
  struct RTCHitN* hit = TX_RAYHITN_HIT(args->rayhit, N);
  for (unsigned int i = 0; i < N; i++) {
    if (args->valid[i] != -1) continue;
    TxBest* best = best_of(args->context, ray, N, i);
    /* In a scene that is not exact, Embree's nearest hit so far (on a quad or triangle, which
     * the bests do not see) is the ray's tfar, and bounds the exact t; in an exact one the
     * tfar is the bests' room, above it. */
    if (offer(u, args->geomID, TX_INVALID_ID, args->primID, load_ray(ray, N, i), best,
              TX_RAYN_F(ray, N, i, RAY_TFAR))) {
      TX_RAYN_F(ray, N, i, RAY_TFAR) = room(best);
      TX_HITN_F(hit, N, i, HIT_NG_X) = 0.0f;
      TX_HITN_F(hit, N, i, HIT_NG_Y) = 0.0f;
      TX_HITN_F(hit, N, i, HIT_NG_Z) = 0.0f;
      TX_HITN_F(hit, N, i, HIT_U) = best->u;
      TX_HITN_F(hit, N, i, HIT_V) = best->v;
      TX_HITN_U(hit, N, i, HIT_PRIM) = args->primID;
      TX_HITN_U(hit, N, i, HIT_GEOM) = args->geomID;
      TX_HITN_U(hit, N, i, HIT_INST0) = args->context->instID[0];
#if defined(RTC_GEOMETRY_INSTANCE_ARRAY)
      TX_HITN_U(hit, N, i, HIT_INST_PRIM0) = args->context->instPrimID[0];
#endif
    } else {
#if TX_EMBREE_MAJOR >= 4
      /* Embree 4 reads valid[i] back: -1 means the callback reported a hit. */
      args->valid[i] = 0;
#endif
    }
  }
}

static void user_occluded(const struct RTCOccludedFunctionNArguments* args) {
  const TxExact* u = (const TxExact*)args->geometryUserPtr;
  const unsigned int N = args->N;
  for (unsigned int i = 0; i < N; i++) {
    if (args->valid[i] != -1) continue;
    if (exact_occludes(u, TX_INVALID_ID, args->primID, load_ray(args->ray, N, i),
                       best_of(args->context, args->ray, N, i))) {
      TX_RAYN_F(args->ray, N, i, RAY_TFAR) = -INFINITY;
    } else {
#if TX_EMBREE_MAJOR >= 4
      args->valid[i] = 0;
#endif
    }
  }
}

unsigned int tx_scene_add_user(TxScene* s, unsigned int n, const void* user, TxBoundsFn bounds,
                               TxIntersectFn exact, unsigned int key_base) {
  RTCDevice device = rtcGetSceneDevice(s->scene);
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
  rtcReleaseDevice(device);
  if (!geom) return TX_INVALID_ID;
  TxExact* u = add_exact(s, user, bounds, exact, key_base);
  if (!u) {
    rtcReleaseGeometry(geom);
    return TX_INVALID_ID;
  }
  rtcSetGeometryUserPrimitiveCount(geom, n);
  rtcSetGeometryUserData(geom, u);
  rtcSetGeometryBoundsFunction(geom, user_bounds, NULL);
  rtcSetGeometryIntersectFunction(geom, user_intersect);
  rtcSetGeometryOccludedFunction(geom, user_occluded);
  return attach(s, geom);
}

int tx_scene_commit(TxScene* s) {
  rtcCommitScene(s->scene);
  RTCDevice device = rtcGetSceneDevice(s->scene);
  int err = (int)rtcGetDeviceError(device);
  rtcReleaseDevice(device);
  return err;
}

/* ---- queries ----------------------------------------------------------------------------- */

static void init_rayhit(struct RTCRayHit* rh, const TxRay* r) {
  rh->ray.org_x = r->org[0];
  rh->ray.org_y = r->org[1];
  rh->ray.org_z = r->org[2];
  rh->ray.tnear = r->tnear;
  rh->ray.dir_x = r->dir[0];
  rh->ray.dir_y = r->dir[1];
  rh->ray.dir_z = r->dir[2];
  rh->ray.time = 0.0f;
  rh->ray.tfar = r->tfar;
  rh->ray.mask = 0xFFFFFFFFu;
  rh->ray.id = 0;
  rh->ray.flags = 0;
  rh->hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
#if defined(RTC_GEOMETRY_INSTANCE_ARRAY)
  rh->hit.instPrimID[0] = RTC_INVALID_GEOMETRY_ID;
#endif
}

static void init_ray(struct RTCRay* ray, const TxRay* r) {
  ray->org_x = r->org[0];
  ray->org_y = r->org[1];
  ray->org_z = r->org[2];
  ray->tnear = r->tnear;
  ray->dir_x = r->dir[0];
  ray->dir_y = r->dir[1];
  ray->dir_z = r->dir[2];
  ray->time = 0.0f;
  ray->tfar = r->tfar;
  ray->mask = 0xFFFFFFFFu;
  ray->id = 0;
  ray->flags = 0;
}

/* How much wider than asked the range Embree searches is, in an exact scene, relative to its
 * ends: Embree's own t for a candidate differs from the exact routine's by the rounding of
 * the enlarged polygon's plane over the cosine at which the ray meets it, and a candidate whose
 * exact t is in range but Embree's just out of it is never proposed. A shadow ray grazing a
 * light's neighbouring triangle (cosine 6e-4) had the exact t 0.99988 in a range ending at
 * 0.9999 and Embree's t 0.99996: the BVH found the triangle in the way and Embree did not.
 * The filters hold every hit to the range as asked. The slack stays below the 1e-4 by which
 * shadow rays stop short of their light (`shadow_ray`): a slack of 1e-2 had Embree propose the
 * light itself to every shadow ray, and halved their rate. */
#define TX_RANGE_SLACK 8e-5f

/* A query's context over `best` (one entry per ray id), each entry reset to the ray's range
 * (`tnear`, `tfar`: Embree's ray's, n of them), which in an exact scene is then widened by
 * TX_RANGE_SLACK for Embree. */
static void start_query(const TxScene* s, TxQuery* q, TxBest* best, float* tnear, float* tfar,
                        size_t n, const TxRay* rays, size_t count) {
#if TX_EMBREE_MAJOR >= 4
  rtcInitRayQueryContext(&q->context);
#else
  rtcInitIntersectContext(&q->context);
#endif
  q->best = best;
  for (size_t k = 0; k < n; k++) {
    best[k].near = tnear[k];
    best[k].limit = tfar[k];
    best[k].t = tfar[k];
    best[k].key = TX_INVALID_ID;
    best[k].geom = TX_INVALID_ID;
    best[k].inst = TX_INVALID_ID;
    /* Lanes beyond the rays given (an unused lane of a packet) keep the last. */
    best[k].ray = rays[k < count ? k : count - 1];
    if (s->exact && tfar[k] >= tnear[k]) {
      tnear[k] = fmaxf(tnear[k] - fabsf(tnear[k]) * TX_RANGE_SLACK, 0.0f);
      tfar[k] += fabsf(tfar[k]) * TX_RANGE_SLACK;
    }
  }
}

static void rtc_intersect1(RTCScene scene, TxQuery* q, struct RTCRayHit* rh) {
#if TX_EMBREE_MAJOR >= 4
  struct RTCIntersectArguments args;
  rtcInitIntersectArguments(&args);
  args.context = &q->context;
  rtcIntersect1(scene, rh, &args);
#else
  rtcIntersect1(scene, &q->context, rh);
#endif
}

static void rtc_occluded1(RTCScene scene, TxQuery* q, struct RTCRay* ray) {
#if TX_EMBREE_MAJOR >= 4
  struct RTCOccludedArguments args;
  rtcInitOccludedArguments(&args);
  args.context = &q->context;
  rtcOccluded1(scene, ray, &args);
#else
  rtcOccluded1(scene, &q->context, ray);
#endif
}

static void rtc_intersect8(const int* valid, RTCScene scene, TxQuery* q, struct RTCRayHit8* rh) {
#if TX_EMBREE_MAJOR >= 4
  struct RTCIntersectArguments args;
  rtcInitIntersectArguments(&args);
  args.context = &q->context;
  rtcIntersect8(valid, scene, rh, &args);
#else
  rtcIntersect8(valid, scene, &q->context, rh);
#endif
}

static void rtc_occluded8(const int* valid, RTCScene scene, TxQuery* q, struct RTCRay8* ray) {
#if TX_EMBREE_MAJOR >= 4
  struct RTCOccludedArguments args;
  rtcInitOccludedArguments(&args);
  args.context = &q->context;
  rtcOccluded8(valid, scene, ray, &args);
#else
  rtcOccluded8(valid, scene, &q->context, ray);
#endif
}

static void write_hit(TxHit* hit, const TxBest* best) {
  hit->t = best->t;
  hit->u = best->u;
  hit->v = best->v;
  hit->geom = best->geom;
  hit->prim = best->prim;
  hit->inst = best->inst;
}

void tx_intersect1(const TxScene* s, const TxRay* r, TxHit* hit) {
  struct RTCRayHit rh;
  init_rayhit(&rh, r);
  TxQuery q;
  TxBest best;
  start_query(s, &q, &best, &rh.ray.tnear, &rh.ray.tfar, 1, r, 1);
  rtc_intersect1(s->scene, &q, &rh);
  if (s->exact) {
    write_hit(hit, &best);
  } else {
    hit->t = rh.ray.tfar;
    hit->u = rh.hit.u;
    hit->v = rh.hit.v;
    hit->geom = rh.hit.geomID;
    hit->prim = rh.hit.primID;
    hit->inst = rh.hit.instID[0];
  }
}

int tx_occluded1(const TxScene* s, const TxRay* r) {
  struct RTCRay ray;
  init_ray(&ray, r);
  TxQuery q;
  TxBest best;
  start_query(s, &q, &best, &ray.tnear, &ray.tfar, 1, r, 1);
  rtc_occluded1(s->scene, &q, &ray);
  return ray.tfar < 0.0f;
}

/* Loads up to 8 rays into an SoA packet; unused lanes are invalid. */
static void load_packet(struct RTCRay8* p, int* valid, const TxRay* rays, size_t count) {
  for (size_t k = 0; k < 8; k++) {
    if (k < count) {
      const TxRay* r = &rays[k];
      valid[k] = -1;
      p->org_x[k] = r->org[0];
      p->org_y[k] = r->org[1];
      p->org_z[k] = r->org[2];
      p->tnear[k] = r->tnear;
      p->dir_x[k] = r->dir[0];
      p->dir_y[k] = r->dir[1];
      p->dir_z[k] = r->dir[2];
      p->tfar[k] = r->tfar;
    } else {
      valid[k] = 0;
      p->org_x[k] = p->org_y[k] = p->org_z[k] = 0.0f;
      p->dir_x[k] = p->dir_y[k] = p->dir_z[k] = 1.0f;
      p->tnear[k] = 0.0f;
      p->tfar[k] = -INFINITY;
    }
    p->time[k] = 0.0f;
    p->mask[k] = 0xFFFFFFFFu;
    p->id[k] = (unsigned int)k;
    p->flags[k] = 0;
  }
}

/* Marks every lane of a hit packet as "no hit yet", as Embree requires before a query. */
static void init_hit_packet(struct RTCHit8* hit) {
  for (size_t k = 0; k < 8; k++) {
    hit->geomID[k] = RTC_INVALID_GEOMETRY_ID;
    hit->instID[0][k] = RTC_INVALID_GEOMETRY_ID;
#if defined(RTC_GEOMETRY_INSTANCE_ARRAY)
    hit->instPrimID[0][k] = RTC_INVALID_GEOMETRY_ID;
#endif
  }
}

void tx_intersect_batch(const TxScene* s, const TxRay* rays, size_t n, TxHit* hits) {
  RTC_ALIGN(32) int valid[8];
  struct RTCRayHit8 rh;
  TxQuery q;
  TxBest best[8];
  for (size_t base = 0; base < n; base += 8) {
    size_t count = n - base < 8 ? n - base : 8;
    load_packet(&rh.ray, valid, rays + base, count);
    init_hit_packet(&rh.hit);
    start_query(s, &q, best, rh.ray.tnear, rh.ray.tfar, 8, rays + base, count);
    rtc_intersect8(valid, s->scene, &q, &rh);
    for (size_t k = 0; k < count; k++) {
      TxHit* h = &hits[base + k];
      if (s->exact) {
        write_hit(h, &best[k]);
      } else {
        h->t = rh.ray.tfar[k];
        h->u = rh.hit.u[k];
        h->v = rh.hit.v[k];
        h->geom = rh.hit.geomID[k];
        h->prim = rh.hit.primID[k];
        h->inst = rh.hit.instID[0][k];
      }
    }
  }
}

void tx_occluded_batch(const TxScene* s, const TxRay* rays, size_t n, unsigned char* hits) {
  RTC_ALIGN(32) int valid[8];
  struct RTCRay8 ray;
  TxQuery q;
  TxBest best[8];
  for (size_t base = 0; base < n; base += 8) {
    size_t count = n - base < 8 ? n - base : 8;
    load_packet(&ray, valid, rays + base, count);
    start_query(s, &q, best, ray.tnear, ray.tfar, 8, rays + base, count);
    rtc_occluded8(valid, s->scene, &q, &ray);
    for (size_t k = 0; k < count; k++) hits[base + k] = ray.tfar[k] < 0.0f;
  }
}

/* ---- baselines --------------------------------------------------------------------------- */

size_t tx_baseline_intersect1(const TxScene* s, const TxRay* rays, size_t n) {
  size_t count = 0;
  for (size_t i = 0; i < n; i++) {
    struct RTCRayHit rh;
    init_rayhit(&rh, &rays[i]);
    TxQuery q;
    TxBest best;
    start_query(s, &q, &best, &rh.ray.tnear, &rh.ray.tfar, 1, &rays[i], 1);
    rtc_intersect1(s->scene, &q, &rh);
    count += (s->exact ? best.geom : rh.hit.geomID) != TX_INVALID_ID;
  }
  return count;
}

size_t tx_baseline_occluded1(const TxScene* s, const TxRay* rays, size_t n) {
  size_t count = 0;
  for (size_t i = 0; i < n; i++) {
    struct RTCRay ray;
    init_ray(&ray, &rays[i]);
    TxQuery q;
    TxBest best;
    start_query(s, &q, &best, &ray.tnear, &ray.tfar, 1, &rays[i], 1);
    rtc_occluded1(s->scene, &q, &ray);
    count += ray.tfar < 0.0f;
  }
  return count;
}

size_t tx_baseline_intersect8(const TxScene* s, const TxRay* rays, size_t n) {
  size_t count = 0;
  RTC_ALIGN(32) int valid[8];
  struct RTCRayHit8 rh;
  for (size_t base = 0; base < n; base += 8) {
    size_t m = n - base < 8 ? n - base : 8;
    load_packet(&rh.ray, valid, rays + base, m);
    init_hit_packet(&rh.hit);
    TxQuery q;
    TxBest best[8];
    start_query(s, &q, best, rh.ray.tnear, rh.ray.tfar, 8, rays + base, m);
    rtc_intersect8(valid, s->scene, &q, &rh);
    for (size_t k = 0; k < m; k++)
      count += (s->exact ? best[k].geom : rh.hit.geomID[k]) != TX_INVALID_ID;
  }
  return count;
}

size_t tx_baseline_occluded8(const TxScene* s, const TxRay* rays, size_t n) {
  size_t count = 0;
  RTC_ALIGN(32) int valid[8];
  struct RTCRay8 ray;
  for (size_t base = 0; base < n; base += 8) {
    size_t m = n - base < 8 ? n - base : 8;
    load_packet(&ray, valid, rays + base, m);
    TxQuery q;
    TxBest best[8];
    start_query(s, &q, best, ray.tnear, ray.tfar, 8, rays + base, m);
    rtc_occluded8(valid, s->scene, &q, &ray);
    for (size_t k = 0; k < m; k++) count += ray.tfar[k] < 0.0f;
  }
  return count;
}
