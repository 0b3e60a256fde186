/* test_world_threads.c: worlds made and stepped on several threads at once
   (POSIX threads; built where CMake finds them). Each world's ids carry
   its own tag, taken atomically at creation: every world refuses every
   other world's ids, however their creations interleaved. */
#include "test_main.h"
#include "tumble.h"

#include <pthread.h>
#include <string.h>

#define THREADS 4
#define WORLDS_EACH 16

typedef struct made {
    tb_world *world[WORLDS_EACH];
    tb_particle_id id[WORLDS_EACH];
    int failures;
} made;

static void *make_and_step(void *arg)
{
    made *m = arg;
    int k, i;
    for (k = 0; k < WORLDS_EACH; ++k) {
        tb_world_def def = tb_default_world_def();
        tb_particle_def p = tb_default_particle_def();
        m->failures += tb_world_create(&def, &m->world[k], NULL, 0) != TB_OK;
        m->failures += tb_world_add_particle(m->world[k], &p, &m->id[k]) != TB_OK;
    }
    for (i = 0; i < 100; ++i)
        for (k = 0; k < WORLDS_EACH; ++k)
            m->failures += tb_world_step(m->world[k], 0.01) != TB_OK;
    return NULL;
}

static void worlds_on_threads_keep_their_ids(void **state)
{
    pthread_t threads[THREADS];
    made m[THREADS];
    int t, k, u, j, refused = 0;
    (void)state;
    memset(m, 0, sizeof m);
    for (t = 0; t < THREADS; ++t)
        assert_int_equal(pthread_create(&threads[t], NULL, make_and_step, &m[t]), 0);
    for (t = 0; t < THREADS; ++t)
        assert_int_equal(pthread_join(threads[t], NULL), 0);
    for (t = 0; t < THREADS; ++t) {
        assert_int_equal(m[t].failures, 0);
        for (k = 0; k < WORLDS_EACH; ++k) {
            double x[3];
            assert_int_equal(tb_particle_position(m[t].world[k], m[t].id[k], x), TB_OK);
            assert_true(x[2] < 0); /* it fell for a second */
            for (u = 0; u < THREADS; ++u)
                for (j = 0; j < WORLDS_EACH; ++j)
                    if (u != t || j != k) {
                        assert_int_equal(tb_particle_position(m[u].world[j], m[t].id[k], x), TB_ERR_STALE_ID);
                        ++refused;
                    }
        }
    }
    assert_int_equal(refused, THREADS * WORLDS_EACH * (THREADS * WORLDS_EACH - 1));
    for (t = 0; t < THREADS; ++t)
        for (k = 0; k < WORLDS_EACH; ++k)
            tb_world_destroy(m[t].world[k]);
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(worlds_on_threads_keep_their_ids),
};
TB_TEST_MAIN(tests)
