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

/* The result of a closest-hit query. geom == TX_INVALID_ID when nothing was hit. */
typedef struct TxHit {
  float t;
  float u;
  float v;
  unsigned int geom;
  unsigned int prim;
} TxHit;

#define TX_INVALID_ID 0xFFFFFFFFu

typedef struct TxDevice TxDevice;
typedef struct TxScene TxScene;

/* Callbacks of user geometry (spheres, rings); they must not allocate. */
typedef void (*TxBoundsFn)(const void* user, unsigned int prim, float* lower3, float* upper3);
/* Returns 1 and writes t, u, v when the primitive is hit in (ray->tnear, ray->tfar). */
typedef int (*TxIntersectFn)(const void* user, unsigned int prim, const TxRay* ray, float* t,
                             float* u, float* v);

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

/* quality: 0 low, 1 medium, 2 high. robust: non-zero for RTC_SCENE_FLAG_ROBUST. */
TxScene* tx_scene_new(TxDevice* device, int quality, int robust);
void tx_scene_release(TxScene* scene);

/* Adds n quads, each given by 4 vertices (12 floats per quad). front_normals: NULL for
 * two-sided quads, else 3 floats per quad; hits from the back side (dot(normal, dir) >= 0)
 * are then rejected by a filter written in C. Returns the geometry id, or TX_INVALID_ID. */
unsigned int tx_scene_add_quads(TxScene* scene, const float* vertices, unsigned int n,
                                const float* front_normals);

/* Adds an indexed triangle mesh: n_vertices * 3 floats, n_triangles * 3 indices. */
unsigned int tx_scene_add_triangles(TxScene* scene, const float* vertices,
                                    unsigned int n_vertices, const unsigned int* indices,
                                    unsigned int n_triangles);

/* Adds n user primitives with the given callbacks. `user` must outlive the scene. */
unsigned int tx_scene_add_user(TxScene* scene, unsigned int n, const void* user,
                               TxBoundsFn bounds, TxIntersectFn intersect);

/* Builds the acceleration structure. Returns 0 on success. */
int tx_scene_commit(TxScene* scene);

void tx_intersect1(const TxScene* scene, const TxRay* ray, TxHit* hit);
int tx_occluded1(const TxScene* scene, const TxRay* ray);

/* Batched queries over n rays, traced as packets of 8 rays. */
void tx_intersect_batch(const TxScene* scene, const TxRay* rays, size_t n, TxHit* hits);
void tx_occluded_batch(const TxScene* scene, const TxRay* rays, size_t n, unsigned char* hits);

/* Baselines for the benchmarks: plain C loops calling Embree directly, with no trilux layer.
 * They measure what the Rust API costs on top of Embree. Return the number of hits. */
size_t tx_baseline_intersect1(const TxScene* scene, const TxRay* rays, size_t n);
size_t tx_baseline_occluded1(const TxScene* scene, const TxRay* rays, size_t n);
size_t tx_baseline_intersect8(const TxScene* scene, const TxRay* rays, size_t n);
size_t tx_baseline_occluded8(const TxScene* scene, const TxRay* rays, size_t n);

#ifdef __cplusplus
}
#endif

#endif
