/* trilux's C shim over Intel Embree 3 and 4.
 *
 * This header names no Embree type: the Rust side sees only these declarations (bindgen), and
 * shim.c hides every difference between the Embree 3 and Embree 4 APIs. */
#ifndef TRILUX_SHIM_H
#define TRILUX_SHIM_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* A ray, laid out exactly as trilux's Rust `Ray` (repr(C)): origin, t_min, direction, t_max. */
typedef struct TxRay {
  float org[3];
  float tnear;
  float dir[3];
  float tfar;
} TxRay;

/* The result of a closest-hit query. geom == TX_INVALID_ID when nothing was hit. On an
 * instance's triangle, inst is the instance's geometry id in the scene queried and prim the
 * triangle's index in its group; inst is TX_INVALID_ID on every other hit. */
typedef struct TxHit {
  float t;
  float u;
  float v;
  unsigned int geom;
  unsigned int prim;
  unsigned int inst;
} TxHit;

#define TX_INVALID_ID 0xFFFFFFFFu

typedef struct TxDevice TxDevice;
typedef struct TxScene TxScene;

/* Callbacks of user geometry (spheres, rings); they must not allocate. */
typedef void (*TxBoundsFn)(const void* user, unsigned int prim, float* lower3, float* upper3);
/* Returns 1 and writes t, u, v when the primitive is hit in (ray->tnear, ray->tfar). */
typedef int (*TxIntersectFn)(const void* user, unsigned int prim, const TxRay* ray, float* t,
                             float* u, float* v);

/* The exact routine of an instanced group's triangle `prim`, placed by the instance of
 * geometry id `inst`, on the ray as the query asked it (in the world: the routine takes it into
 * the group's space itself, as the built-in BVH does). Returns 1 and writes t, u, v and the
 * hit's key in the tie rule when it is hit in (ray->tnear, ray->tfar). */
typedef int (*TxInstancedFn)(const void* user, unsigned int inst, unsigned int prim,
                             const TxRay* ray, float* t, float* u, float* v, unsigned int* key);

/* Returns the Embree major version the shim was compiled against. */
int tx_embree_major(void);

/* Flush-to-zero and denormals-are-zero on the calling thread, as Embree recommends. */
void tx_set_flush_denormals(void);

/* Creates a device; NULL on failure (the reason is in tx_last_error). */
TxDevice* tx_device_new(const char* config);
void tx_device_release(TxDevice* device);

/* Copies the most recent Embree error message (from the error callback) into buf and clears
 * it. Returns the message length, 0 when there was none. */
size_t tx_last_error(char* buf, size_t len);

/* quality: 0 low, 1 medium, 2 high. robust: non-zero for RTC_SCENE_FLAG_ROBUST. exact:
 * non-zero for hits decided by trilux's exact routines (below); zero for Embree's own test,
 * one-sided quads then filtered by their front normals. */
TxScene* tx_scene_new(TxDevice* device, int quality, int robust, int exact);
void tx_scene_release(TxScene* scene);

/* In an exact scene every primitive's hits are decided by trilux's exact routine `exact` (the
 * one the built-in BVH runs), called with the primitive's index; `user` must outlive the
 * scene (user geometry always runs it). Embree only
 * proposes candidates: quads and triangles are handed to it slightly enlarged (see shim.c), so
 * that it proposes every primitive the exact routine could accept. Of the accepted hits a
 * query answers the nearest, and of equally near ones the one with the smallest
 * `key_base | prim` -- the built-in BVH's rule -- so that both backends answer the same
 * primitive at the same t.
 *
 * Adds n quads, each given by 4 vertices (12 floats per quad). front_normals: NULL for
 * two-sided quads, else 3 floats per quad, read when the scene is not exact (hits from the
 * back side, dot(normal, dir) >= 0, are then rejected by a filter written in C; the exact
 * routine makes that test itself). Returns the geometry id, or TX_INVALID_ID. */
unsigned int tx_scene_add_quads(TxScene* scene, const float* vertices, unsigned int n,
                                const float* front_normals, const void* user,
                                TxIntersectFn exact, unsigned int key_base);

/* Adds an indexed triangle mesh: n_triangles * 3 indices into vertices (3 floats each).
 * front_normals: NULL for triangles opaque from both sides, else 3 floats per triangle, read
 * as tx_scene_add_quads reads its own. */
unsigned int tx_scene_add_triangles(TxScene* scene, const float* vertices,
                                    const unsigned int* indices, unsigned int n_triangles,
                                    const float* front_normals, const void* user,
                                    TxIntersectFn exact, unsigned int key_base);

/* Adds a group's triangles (in its own space) to `group`, a scene that instances place
 * (tx_scene_add_instance); in an exact scene `exact` decides their hits, on the query's own
 * ray. */
unsigned int tx_scene_add_group_triangles(TxScene* group, const float* vertices,
                                          const unsigned int* indices, unsigned int n_triangles,
                                          const void* user, TxInstancedFn exact);

/* Adds to `scene` an instance of `group` (committed, released after `scene`), placed by
 * `to_world`: 12 floats, the columns of a 3x4 matrix (the linear part's three, then the
 * translation). Returns the instance's geometry id, or TX_INVALID_ID. */
unsigned int tx_scene_add_instance(TxScene* scene, const TxScene* group, const float* to_world);

/* Adds n user primitives (spheres, rings) with the given callbacks. */
unsigned int tx_scene_add_user(TxScene* scene, unsigned int n, const void* user,
                               TxBoundsFn bounds, TxIntersectFn exact, unsigned int key_base);

/* Builds the acceleration structure. Returns 0 on success. */
int tx_scene_commit(TxScene* scene);

void tx_intersect1(const TxScene* scene, const TxRay* ray, TxHit* hit);
int tx_occluded1(const TxScene* scene, const TxRay* ray);

/* Batched queries over n rays, traced as packets of 8 rays. */
void tx_intersect_batch(const TxScene* scene, const TxRay* rays, size_t n, TxHit* hits);
void tx_occluded_batch(const TxScene* scene, const TxRay* rays, size_t n, unsigned char* hits);

/* Baselines for the benchmarks: plain C loops calling Embree directly, with no Rust layer
 * around the query (an exact scene still calls its exact routines). They measure what the
 * Rust API costs on top of Embree. Return the number of hits. */
size_t tx_baseline_intersect1(const TxScene* scene, const TxRay* rays, size_t n);
size_t tx_baseline_occluded1(const TxScene* scene, const TxRay* rays, size_t n);
size_t tx_baseline_intersect8(const TxScene* scene, const TxRay* rays, size_t n);
size_t tx_baseline_occluded8(const TxScene* scene, const TxRay* rays, size_t n);

#ifdef __cplusplus
}
#endif

#endif
