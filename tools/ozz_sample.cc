// Samples an ozz animation at given times and prints every joint's model-space matrix
// (column-major, 16 floats) per time: "name m0 ... m15". Usage: ozz_sample skeleton.ozz anim.ozz t0 t1 ...
#include <cstdio>
#include <cstdlib>
#include "ozz/animation/runtime/animation.h"
#include "ozz/animation/runtime/skeleton.h"
#include "ozz/animation/runtime/sampling_job.h"
#include "ozz/animation/runtime/local_to_model_job.h"
#include "ozz/base/io/archive.h"
#include "ozz/base/io/stream.h"
#include "ozz/base/maths/soa_transform.h"
#include "ozz/base/maths/simd_math.h"
#include "ozz/base/containers/vector.h"
#include "ozz/base/span.h"
int main(int argc, char** argv) {
  ozz::animation::Skeleton skel; ozz::animation::Animation anim;
  { ozz::io::File f(argv[1], "rb"); ozz::io::IArchive a(&f); a >> skel; }
  { ozz::io::File f(argv[2], "rb"); ozz::io::IArchive a(&f); a >> anim; }
  int n = skel.num_joints();
  ozz::vector<ozz::math::SoaTransform> locals(skel.num_soa_joints());
  ozz::vector<ozz::math::Float4x4> models(n);
  ozz::animation::SamplingJob::Context ctx(anim.num_tracks());
  printf("duration %.9g joints %d\n", anim.duration(), n);
  for (int i = 3; i < argc; ++i) {
    float t = strtof(argv[i], nullptr);
    ozz::animation::SamplingJob sj; sj.animation = &anim; sj.context = &ctx;
    sj.ratio = anim.duration() > 0 ? t / anim.duration() : 0.f; sj.output = ozz::make_span(locals);
    if (!sj.Run()) { fprintf(stderr, "sampling failed\n"); return 1; }
    ozz::animation::LocalToModelJob lj; lj.skeleton = &skel; lj.input = ozz::make_span(locals); lj.output = ozz::make_span(models);
    if (!lj.Run()) { fprintf(stderr, "ltm failed\n"); return 1; }
    printf("time %.9g\n", t);
    for (int j = 0; j < n; ++j) {
      float m[16];
      for (int c = 0; c < 4; ++c) ozz::math::StorePtrU(models[j].cols[c], m + 4 * c);
      printf("%s", skel.joint_names()[j]);
      for (int k = 0; k < 16; ++k) printf(" %.9g", m[k]);
      printf("\n");
    }
  }
  return 0;
}
