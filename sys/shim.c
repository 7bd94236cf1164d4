/* trilux's C shim over Intel Embree 3 and 4: see shim.h for the interface.
 *
 * Everything version-specific lives here, behind TX_EMBREE_MAJOR (set by build.rs) and
 * RTC_GEOMETRY_INSTANCE_ARRAY (Embree 4.3+ built with instance arrays: hits are larger). The hot
 * callbacks stay in C: back-face rejection of one-sided quads is a filter over a plain array of
 * normals; user geometry (spheres, rings) unpacks each ray and calls trilux's Rust intersection
 * routine through a function pointer, so Embree and the built-in BVH run the same arithmetic. */
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
/* Embree 4.3+ built with instance arrays has instPrimID after the instID levels. */
#define HIT_INST_PRIM0 (HIT_INST0 + RTC_MAX_INSTANCE_LEVEL_COUNT)
#define TX_RAYHITN_RAY(rh, N) ((struct RTCRayN*)(rh))
#define TX_RAYHITN_HIT(rh, N) ((struct RTCHitN*)&((float*)(rh))[12 * (N)])

#define TX_MAX_USER_GEOMETRIES 8

struct TxDevice {
  RTCDevice device;
};

typedef struct TxUser {
  const void* user;
  TxBoundsFn bounds;
  TxIntersectFn intersect;
} TxUser;

struct TxScene {
  RTCScene scene;
  float* quad_normals;
  TxUser users[TX_MAX_USER_GEOMETRIES];
  unsigned int n_users;
};

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

TxScene* tx_scene_new(TxDevice* device, int quality, int robust) {
  RTCScene scene = rtcNewScene(device->device);
  if (!scene) return NULL;
  TxScene* s = (TxScene*)calloc(1, sizeof *s);
  if (!s) {
    rtcReleaseScene(scene);
    record_error("trilux shim: out of memory");
    return NULL;
  }
  s->scene = scene;
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
  free(scene->quad_normals);
  free(scene);
}

/* Rejects hits on the back side of one-sided quads: the geometry's user data is the array of
 * their front normals. */
static void quad_front_filter(const struct RTCFilterFunctionNArguments* args) {
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

static unsigned int attach(TxScene* s, RTCGeometry geom) {
  rtcCommitGeometry(geom);
  unsigned int id = rtcAttachGeometry(s->scene, geom);
  rtcReleaseGeometry(geom);
  return id;
}

unsigned int tx_scene_add_quads(TxScene* s, const float* vertices, unsigned int n,
                                const float* front_normals) {
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
  memcpy(vb, vertices, 12 * sizeof(float) * (size_t)n);
  for (unsigned int i = 0; i < 4 * n; i++) ib[i] = i;
  if (front_normals) {
    if (s->quad_normals) {
      record_error("trilux shim: only one one-sided quad geometry per scene");
      rtcReleaseGeometry(geom);
      return TX_INVALID_ID;
    }
    s->quad_normals = (float*)malloc(3 * sizeof(float) * (size_t)n);
    if (!s->quad_normals) {
      rtcReleaseGeometry(geom);
      record_error("trilux shim: out of memory");
      return TX_INVALID_ID;
    }
    memcpy(s->quad_normals, front_normals, 3 * sizeof(float) * (size_t)n);
    rtcSetGeometryUserData(geom, s->quad_normals);
    rtcSetGeometryIntersectFilterFunction(geom, quad_front_filter);
    rtcSetGeometryOccludedFilterFunction(geom, quad_front_filter);
  }
  return attach(s, geom);
}

unsigned int tx_scene_add_triangles(TxScene* s, const float* vertices, unsigned int n_vertices,
                                    const unsigned int* indices, unsigned int n_triangles) {
  RTCDevice device = rtcGetSceneDevice(s->scene);
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcReleaseDevice(device);
  if (!geom) return TX_INVALID_ID;
  /* Embree may read 16 bytes at the last vertex: the buffer it allocates itself is padded. */
  float* vb = (float*)rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                              3 * sizeof(float), n_vertices);
  unsigned int* ib = (unsigned int*)rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned int), n_triangles);
  if (!vb || !ib) {
    rtcReleaseGeometry(geom);
    return TX_INVALID_ID;
  }
  memcpy(vb, vertices, 3 * sizeof(float) * (size_t)n_vertices);
  memcpy(ib, indices, 3 * sizeof(unsigned int) * (size_t)n_triangles);
  return attach(s, geom);
}

/* ---- user geometry ----------------------------------------------------------------------- */

static void user_bounds(const struct RTCBoundsFunctionArguments* args) {
  const TxUser* u = (const TxUser*)args->geometryUserPtr;
  float lo[3], hi[3];
  u->bounds(u->user, args->primID, lo, hi);
  args->bounds_o->lower_x = lo[0];
  args->bounds_o->lower_y = lo[1];
  args->bounds_o->lower_z = lo[2];
  args->bounds_o->upper_x = hi[0];
  args->bounds_o->upper_y = hi[1];
  args->bounds_o->upper_z = hi[2];
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

static void user_intersect(const struct RTCIntersectFunctionNArguments* args) {
  const TxUser* u = (const TxUser*)args->geometryUserPtr;
  const unsigned int N = args->N;
  struct RTCRayN* ray = TX_RAYHITN_RAY(args->rayhit, N);
  struct RTCHitN* hit = TX_RAYHITN_HIT(args->rayhit, N);
  for (unsigned int i = 0; i < N; i++) {
    if (args->valid[i] != -1) continue;
    TxRay r = load_ray(ray, N, i);
    float t, hu, hv;
    if (u->intersect(u->user, args->primID, &r, &t, &hu, &hv)) {
      TX_RAYN_F(ray, N, i, RAY_TFAR) = t;
      TX_HITN_F(hit, N, i, HIT_NG_X) = 0.0f;
      TX_HITN_F(hit, N, i, HIT_NG_Y) = 0.0f;
      TX_HITN_F(hit, N, i, HIT_NG_Z) = 0.0f;
      TX_HITN_F(hit, N, i, HIT_U) = hu;
      TX_HITN_F(hit, N, i, HIT_V) = hv;
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
  const TxUser* u = (const TxUser*)args->geometryUserPtr;
  const unsigned int N = args->N;
  for (unsigned int i = 0; i < N; i++) {
    if (args->valid[i] != -1) continue;
    TxRay r = load_ray(args->ray, N, i);
    float t, hu, hv;
    if (u->intersect(u->user, args->primID, &r, &t, &hu, &hv)) {
      TX_RAYN_F(args->ray, N, i, RAY_TFAR) = -INFINITY;
    } else {
#if TX_EMBREE_MAJOR >= 4
      args->valid[i] = 0;
#endif
    }
  }
}

unsigned int tx_scene_add_user(TxScene* s, unsigned int n, const void* user, TxBoundsFn bounds,
                               TxIntersectFn intersect) {
  if (s->n_users >= TX_MAX_USER_GEOMETRIES) {
    record_error("trilux shim: too many user geometries in one scene");
    return TX_INVALID_ID;
  }
  RTCDevice device = rtcGetSceneDevice(s->scene);
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
  rtcReleaseDevice(device);
  if (!geom) return TX_INVALID_ID;
  TxUser* u = &s->users[s->n_users++];
  u->user = user;
  u->bounds = bounds;
  u->intersect = intersect;
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

static void rtc_intersect1(RTCScene scene, struct RTCRayHit* rh) {
#if TX_EMBREE_MAJOR >= 4
  rtcIntersect1(scene, rh, NULL);
#else
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  rtcIntersect1(scene, &ctx, rh);
#endif
}

static void rtc_occluded1(RTCScene scene, struct RTCRay* ray) {
#if TX_EMBREE_MAJOR >= 4
  rtcOccluded1(scene, ray, NULL);
#else
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  rtcOccluded1(scene, &ctx, ray);
#endif
}

static void rtc_intersect8(const int* valid, RTCScene scene, struct RTCRayHit8* rh) {
#if TX_EMBREE_MAJOR >= 4
  rtcIntersect8(valid, scene, rh, NULL);
#else
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  rtcIntersect8(valid, scene, &ctx, rh);
#endif
}

static void rtc_occluded8(const int* valid, RTCScene scene, struct RTCRay8* ray) {
#if TX_EMBREE_MAJOR >= 4
  rtcOccluded8(valid, scene, ray, NULL);
#else
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  rtcOccluded8(valid, scene, &ctx, ray);
#endif
}

void tx_intersect1(const TxScene* s, const TxRay* r, TxHit* hit) {
  struct RTCRayHit rh;
  init_rayhit(&rh, r);
  rtc_intersect1(s->scene, &rh);
  hit->t = rh.ray.tfar;
  hit->u = rh.hit.u;
  hit->v = rh.hit.v;
  hit->geom = rh.hit.geomID;
  hit->prim = rh.hit.primID;
}

int tx_occluded1(const TxScene* s, const TxRay* r) {
  struct RTCRay ray;
  init_ray(&ray, r);
  rtc_occluded1(s->scene, &ray);
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
    p->id[k] = 0;
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
  for (size_t base = 0; base < n; base += 8) {
    size_t count = n - base < 8 ? n - base : 8;
    load_packet(&rh.ray, valid, rays + base, count);
    init_hit_packet(&rh.hit);
    rtc_intersect8(valid, s->scene, &rh);
    for (size_t k = 0; k < count; k++) {
      TxHit* h = &hits[base + k];
      h->t = rh.ray.tfar[k];
      h->u = rh.hit.u[k];
      h->v = rh.hit.v[k];
      h->geom = rh.hit.geomID[k];
      h->prim = rh.hit.primID[k];
    }
  }
}

void tx_occluded_batch(const TxScene* s, const TxRay* rays, size_t n, unsigned char* hits) {
  RTC_ALIGN(32) int valid[8];
  struct RTCRay8 ray;
  for (size_t base = 0; base < n; base += 8) {
    size_t count = n - base < 8 ? n - base : 8;
    load_packet(&ray, valid, rays + base, count);
    rtc_occluded8(valid, s->scene, &ray);
    for (size_t k = 0; k < count; k++) hits[base + k] = ray.tfar[k] < 0.0f;
  }
}

/* ---- baselines --------------------------------------------------------------------------- */

size_t tx_baseline_intersect1(const TxScene* s, const TxRay* rays, size_t n) {
  size_t count = 0;
  for (size_t i = 0; i < n; i++) {
    struct RTCRayHit rh;
    init_rayhit(&rh, &rays[i]);
    rtc_intersect1(s->scene, &rh);
    count += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
  }
  return count;
}

size_t tx_baseline_occluded1(const TxScene* s, const TxRay* rays, size_t n) {
  size_t count = 0;
  for (size_t i = 0; i < n; i++) {
    struct RTCRay ray;
    init_ray(&ray, &rays[i]);
    rtc_occluded1(s->scene, &ray);
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
    rtc_intersect8(valid, s->scene, &rh);
    for (size_t k = 0; k < m; k++) count += rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
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
    rtc_occluded8(valid, s->scene, &ray);
    for (size_t k = 0; k < m; k++) count += ray.tfar[k] < 0.0f;
  }
  return count;
}
