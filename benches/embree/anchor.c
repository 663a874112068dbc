/* The Embree anchor (benches/RESULTS.md, "The anchors"), re-measured on this machine beside
 * `pathwave bench-rays`: the same 1M-triangle torus knot, 1024x1024 primary rays through pixel
 * centres in 8x8 tiles, one cosine-distributed bounce per hit (offset 1e-4 along the geometric
 * normal turned to face the camera), single-ray rtcIntersect1 on 1 and 2 threads, median of 3.
 * Build: benches/embree/run.sh (needs Debian's libembree-dev 3.13.5). */
#include <embree3/rtcore.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef struct { float x, y, z; } V;
static V v3(float x, float y, float z) { V r = {x, y, z}; return r; }
static V add(V a, V b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static V sub(V a, V b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static V mul(V a, float s) { return v3(a.x * s, a.y * s, a.z * s); }
static float dot(V a, V b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static V cross(V a, V b) { return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x); }
static V norm(V a) { return mul(a, 1.0f / sqrtf(dot(a, a))); }

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

typedef struct { V o, d; } Ray;
typedef struct {
  RTCScene scene;
  Ray *rays;
  size_t n, begin, end;
  float *t;
  V *ng;
} Job;

static void *trace(void *arg) {
  Job *j = arg;
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  for (size_t i = j->begin; i < j->end; i++) {
    struct RTCRayHit rh;
    memset(&rh, 0, sizeof rh);
    rh.ray.org_x = j->rays[i].o.x; rh.ray.org_y = j->rays[i].o.y; rh.ray.org_z = j->rays[i].o.z;
    rh.ray.dir_x = j->rays[i].d.x; rh.ray.dir_y = j->rays[i].d.y; rh.ray.dir_z = j->rays[i].d.z;
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = INFINITY;
    rh.ray.mask = -1;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(j->scene, &ctx, &rh);
    if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
      j->t[i] = rh.ray.tfar;
      j->ng[i] = v3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
    } else {
      j->t[i] = INFINITY;
    }
  }
  return NULL;
}

/* Mrays/s, median of 3; fills t and ng. */
static double run(RTCScene scene, Ray *rays, size_t n, int threads, float *t, V *ng) {
  double rates[3];
  for (int r = 0; r < 3; r++) {
    pthread_t th[8];
    Job jobs[8];
    double start = now();
    for (int k = 0; k < threads; k++) {
      jobs[k] = (Job){scene, rays, n, n * k / threads, n * (k + 1) / threads, t, ng};
      pthread_create(&th[k], NULL, trace, &jobs[k]);
    }
    for (int k = 0; k < threads; k++) pthread_join(th[k], NULL);
    rates[r] = n / (now() - start) / 1e6;
  }
  for (int a = 0; a < 3; a++)
    for (int b = a + 1; b < 3; b++)
      if (rates[b] < rates[a]) { double x = rates[a]; rates[a] = rates[b]; rates[b] = x; }
  return rates[1];
}

static uint32_t hash(uint32_t x) {
  x ^= x >> 16; x *= 0x7feb352dU; x ^= x >> 15; x *= 0x846ca68bU; return x ^ (x >> 16);
}

int main(int argc, char **argv) {
  /* Optional: rings and segments of the knot (default 2000 x 250). */
  const int rings = argc > 2 ? atoi(argv[1]) : 2000, segs = argc > 2 ? atoi(argv[2]) : 250, size = 1024;
  RTCDevice dev = rtcNewDevice("threads=2");
  RTCScene scene = rtcNewScene(dev);
  rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_MEDIUM);
  RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
  float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, rings * segs);
  unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, 2 * rings * segs);
  for (int i = 0; i < rings; i++) {
    double t = 2 * M_PI * i / rings;
    double s2 = sin(2 * t), c2 = cos(2 * t), s3 = sin(3 * t), c3 = cos(3 * t);
    double r = c3 + 2, r1 = -3 * s3, r2 = -9 * c3;
    double c[3] = {r * c2, r * s2, -s3};
    double d1[3] = {r1 * c2 - 2 * r * s2, r1 * s2 + 2 * r * c2, -3 * c3};
    double d2[3] = {r2 * c2 - 4 * r1 * s2 - 4 * r * c2, r2 * s2 + 4 * r1 * c2 - 4 * r * s2, 9 * s3};
    double l = sqrt(d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2]);
    double T[3] = {d1[0] / l, d1[1] / l, d1[2] / l};
    double k = d2[0] * T[0] + d2[1] * T[1] + d2[2] * T[2];
    double N[3] = {d2[0] - k * T[0], d2[1] - k * T[1], d2[2] - k * T[2]};
    l = sqrt(N[0] * N[0] + N[1] * N[1] + N[2] * N[2]);
    for (int a = 0; a < 3; a++) N[a] /= l;
    double B[3] = {T[1] * N[2] - T[2] * N[1], T[2] * N[0] - T[0] * N[2], T[0] * N[1] - T[1] * N[0]};
    for (int j = 0; j < segs; j++) {
      double th = 2 * M_PI * j / segs;
      double rad = 0.4 * (1 + 0.08 * sin(60 * t) * sin(6 * th));
      for (int a = 0; a < 3; a++) vb[3 * (i * segs + j) + a] = c[a] + rad * (cos(th) * N[a] + sin(th) * B[a]);
    }
  }
  for (int i = 0, m = 0; i < rings; i++)
    for (int j = 0; j < segs; j++) {
      unsigned a = i * segs + j, b = ((i + 1) % rings) * segs + j;
      unsigned cc = ((i + 1) % rings) * segs + (j + 1) % segs, d = i * segs + (j + 1) % segs;
      unsigned tri[6] = {a, b, cc, a, cc, d};
      memcpy(ib + 6 * m++, tri, sizeof tri);
    }
  rtcCommitGeometry(g);
  rtcAttachGeometry(scene, g);
  double start = now();
  rtcCommitScene(scene);
  printf("knot: %d triangles, build (medium, 2 threads) %.3f s\n", 2 * rings * segs, now() - start);

  size_t n = (size_t)size * size;
  Ray *prim = malloc(n * sizeof(Ray)), *bounce = malloc(n * sizeof(Ray));
  float *t = malloc(n * sizeof(float));
  V *ng = malloc(n * sizeof(V));
  V from = v3(0, -3, 7.5f), w = norm(from), u = norm(cross(v3(0, 1, 0), w)), vv = cross(w, u);
  float half = tanf(45.0f * (float)M_PI / 360.0f);
  size_t m = 0;
  for (int ty = 0; ty < size; ty += 8)
    for (int tx = 0; tx < size; tx += 8)
      for (int y = ty; y < ty + 8; y++)
        for (int x = tx; x < tx + 8; x++) {
          float sx = (2.0f * (x + 0.5f) / size - 1.0f) * half, sy = (1.0f - 2.0f * (y + 0.5f) / size) * half;
          prim[m].o = from;
          prim[m++].d = norm(sub(add(mul(u, sx), mul(vv, sy)), w));
        }
  printf("| rays | count | hit fraction | Mrays/s 1t | Mrays/s 2t |\n|---|---|---|---|---|\n");
  double p1 = run(scene, prim, n, 1, t, ng), p2 = run(scene, prim, n, 2, t, ng);
  size_t hits = 0, nb = 0;
  for (size_t i = 0; i < n; i++) {
    if (!isfinite(t[i])) continue;
    hits++;
    V d = prim[i].d, nn = norm(ng[i]);
    if (dot(nn, d) > 0) nn = mul(nn, -1);
    V p = add(add(prim[i].o, mul(d, t[i])), mul(nn, 1e-4f));
    uint32_t a = hash((uint32_t)i * 2 + 0x9e3779b9U), b = hash(a ^ 0x5bd1e995U);
    float ux = (a >> 8) / 16777216.0f, uy = (b >> 8) / 16777216.0f;
    V t1 = fabsf(nn.x) > 0.9f ? norm(cross(v3(0, 1, 0), nn)) : norm(cross(v3(1, 0, 0), nn));
    V t2 = cross(nn, t1);
    float rr = sqrtf(ux), phi = 2 * (float)M_PI * uy;
    bounce[nb].o = p;
    bounce[nb++].d = add(add(mul(t1, rr * cosf(phi)), mul(t2, rr * sinf(phi))), mul(nn, sqrtf(fmaxf(0, 1 - ux))));
  }
  printf("| primary | %zu | %.3f | %.2f | %.2f |\n", n, (double)hits / n, p1, p2);
  double b1 = run(scene, bounce, nb, 1, t, ng), b2 = run(scene, bounce, nb, 2, t, ng);
  size_t bh = 0;
  for (size_t i = 0; i < nb; i++) bh += isfinite(t[i]);
  printf("| diffuse bounce | %zu | %.3f | %.2f | %.2f |\n", nb, (double)bh / nb, b1, b2);
  return 0;
}
