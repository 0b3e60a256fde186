/* heap_scenes.h: scenes cut from bench_robustness's heaps, the poses to
   the last digit, shared by the tests and the benchmarks (header only;
   no ODE). */
#ifndef TB_HEAP_SCENES_H
#define TB_HEAP_SCENES_H

/* Box 304 of the heap of 500 (bench_robustness's generator, sleep off) as
   it lay at 19 s across boxes 56 and 184, all on the ground: box 56's top
   edge along its bottom face, a corner of 184 under it. Per box: the
   position (m), the orientation (w, x, y, z), the half extents (m); boxes
   of 1000 kg/m^3, the first 113 kg (docs/notes.md, "A box rocking on two
   corners"; test_contacts_heaps.box_across_two_rests, bench_robustness
   bridge). */
static const double HEAP_BRIDGE[3][10] = {
    { -3.4511684436423731, 2.4798052644161608, 0.57810428672741243, -0.60525992118936112, 0.41329601418254786,
      -0.56067537968134917, -0.3853439386857444, 0.27103454111600134, 0.2486964318183551, 0.21014597811792565 },
    { -2.9811100232981085, 2.4023306555676807, 0.16432440522538311, 0.0093560484185105947, 0.012660970887329592,
      -0.70763700997492196, -0.70640075473341113, 0.18996807681507222, 0.16467683148478443, 0.27162024693041942 },
    { -3.9071323742333011, 2.4919471796091224, 0.14258862969679842, 0.56916542335438469, -0.41899061134116666,
      0.5694697441683324, 0.41976398004430227, 0.14321479440194843, 0.26542033862712555, 0.18640004763695872 }
};

#endif
