// bullet_contacts.cpp: the pyramid and the pile of ode_contacts.h in
// Bullet 3.24 with its defaults (bullet_contacts.h says what is fixed).
#include "bullet_contacts.h"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <memory>
#include <new>
#include <vector>

namespace {

double now_ms()
{
    timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return 1e3 * (double)ts.tv_sec + 1e-6 * (double)ts.tv_nsec;
}

double median(std::vector<double> v)
{
    if (v.empty())
        return -1;
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// A dynamics world, its plane, and the bodies it owns.
class scene {
  public:
    scene(double gravity, double friction)
        : dispatcher(&configuration),
          world(&dispatcher, &broadphase, &solver, &configuration), plane(btVector3(0, 0, 1), 0)
    {
        world.setGravity(btVector3(0, 0, (btScalar)-gravity));
        btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, &plane);
        info.m_friction = (btScalar)friction;
        bodies.emplace_back(new btRigidBody(info));
        world.addRigidBody(bodies.back().get());
    }
    ~scene()
    {
        for (auto &b : bodies)
            world.removeRigidBody(b.get());
    }
    // A body of `shape` (owned from now on) at x with orientation q (w, x,
    // y, z), mass m and principal inertia I along the shape's axes.
    btRigidBody *add(btCollisionShape *shape, const double x[3], const double q[4], double m, const double I[3],
                     double friction, int sleep)
    {
        shapes.emplace_back(shape);
        btTransform start(btQuaternion((btScalar)q[1], (btScalar)q[2], (btScalar)q[3], (btScalar)q[0]),
                          btVector3((btScalar)x[0], (btScalar)x[1], (btScalar)x[2]));
        motions.emplace_back(new btDefaultMotionState(start));
        btRigidBody::btRigidBodyConstructionInfo info((btScalar)m, motions.back().get(), shape,
                                                      btVector3((btScalar)I[0], (btScalar)I[1], (btScalar)I[2]));
        info.m_friction = (btScalar)friction;
        info.m_restitution = 0;
        bodies.emplace_back(new btRigidBody(info));
        btRigidBody *b = bodies.back().get();
        if (!sleep)
            b->setActivationState(DISABLE_DEACTIVATION);
        world.addRigidBody(b);
        return b;
    }
    // One step of h, timed (ms); the contact points it left.
    double step(double h, int *points)
    {
        const double t0 = now_ms();
        world.stepSimulation((btScalar)h, 0);
        const double t = now_ms() - t0;
        int n = 0;
        for (int i = 0; i < dispatcher.getNumManifolds(); ++i)
            n += dispatcher.getManifoldByIndexInternal(i)->getNumContacts();
        *points = n;
        return t;
    }
    // Whether every body but the plane is inactive (asleep).
    bool asleep() const
    {
        for (size_t i = 1; i < bodies.size(); ++i)
            if (bodies[i]->isActive())
                return false;
        return true;
    }

  private:
    btDefaultCollisionConfiguration configuration;
    btCollisionDispatcher dispatcher;
    btDbvtBroadphase broadphase;
    btSequentialImpulseConstraintSolver solver;
    btDiscreteDynamicsWorld world;
    btStaticPlaneShape plane;
    std::vector<std::unique_ptr<btCollisionShape>> shapes;
    std::vector<std::unique_ptr<btDefaultMotionState>> motions;
    std::vector<std::unique_ptr<btRigidBody>> bodies;
};

// Steps s `steps` times, filling out's timing and contacts; with
// asleep_steps > 0, times that many more once every body sleeps.
void run(scene &s, double h, int steps, int asleep_steps, bullet_run *out)
{
    std::vector<double> ms;
    double contacts = 0;
    int points;
    ms.reserve((size_t)steps);
    out->asleep_after = -1;
    out->asleep_ms = -1;
    for (int i = 0; i < steps; ++i) {
        ms.push_back(s.step(h, &points));
        contacts += points;
        if (out->asleep_after < 0 && s.asleep())
            out->asleep_after = i + 1;
    }
    out->ms_median = median(ms);
    out->ms_mean = 0;
    for (double t : ms)
        out->ms_mean += t / (double)steps;
    out->contacts_mean = contacts / (double)steps;
    if (asleep_steps > 0 && out->asleep_after > 0) {
        std::vector<double> rest;
        for (int i = 0; i < asleep_steps; ++i)
            rest.push_back(s.step(h, &points));
        out->asleep_ms = median(rest);
    }
}

} // namespace

extern "C" int bullet_pyramid(const ode_pyramid_def *def, int sleep, int asleep_steps, bullet_run *out)
{
    const int count = ode_pyramid_boxes(def->levels);
    if (count <= 0 || !(def->hz > 0) || !(def->duration > 0))
        return 0;
    try {
        std::vector<double> pos(3 * (size_t)count);
        if (ode_pyramid_positions(def, reinterpret_cast<double(*)[3]>(pos.data())) != count)
            return 0;
        const double friction = std::sqrt(def->mu), half = def->edge / 2, q[4] = { 1, 0, 0, 0 };
        const double I[3] = { def->mass * def->edge * def->edge / 6, def->mass * def->edge * def->edge / 6,
                              def->mass * def->edge * def->edge / 6 };
        std::unique_ptr<scene> s(new scene(def->gravity, friction));
        btRigidBody *top = nullptr;
        for (int i = 0; i < count; ++i)
            top = s->add(new btBoxShape(btVector3((btScalar)half, (btScalar)half, (btScalar)half)), &pos[3 * (size_t)i],
                         q, def->mass, I, friction, sleep);
        run(*s, 1 / def->hz, (int)std::ceil(def->duration * def->hz), sleep ? asleep_steps : 0, out);
        const btVector3 x = top->getCenterOfMassPosition();
        const double *x0 = &pos[3 * (size_t)(count - 1)];
        out->top_sink = x0[2] - (double)x.z();
        out->top_drift = std::hypot((double)x.x() - x0[0], (double)x.y() - x0[1]);
        out->below = 0;
        return 1;
    } catch (...) {
        return 0;
    }
}

extern "C" int bullet_pile(const ode_pile_def *def, const ode_shape *shapes, int sleep, bullet_run *out)
{
    if (def->count <= 0 || !(def->hz > 0) || def->steps <= 0)
        return 0;
    try {
        const double friction = std::sqrt(def->mu);
        std::unique_ptr<scene> s(new scene(def->gravity, friction));
        std::vector<btRigidBody *> bodies;
        for (int i = 0; i < def->count; ++i) {
            const ode_shape &o = shapes[i];
            btCollisionShape *shape =
                o.kind == ODE_SHAPE_SPHERE ? static_cast<btCollisionShape *>(new btSphereShape((btScalar)o.radius))
                : o.kind == ODE_SHAPE_BOX
                    ? static_cast<btCollisionShape *>(
                          new btBoxShape(btVector3((btScalar)o.half[0], (btScalar)o.half[1], (btScalar)o.half[2])))
                    : static_cast<btCollisionShape *>(new btCapsuleShapeZ((btScalar)o.radius, (btScalar)(2 * o.half[2])));
            bodies.push_back(s->add(shape, o.position, o.orientation, o.mass, o.inertia, friction, sleep));
        }
        run(*s, 1 / def->hz, def->steps, 0, out);
        out->top_sink = out->top_drift = 0;
        out->below = 0;
        for (btRigidBody *b : bodies)
            out->below += b->getCenterOfMassPosition().z() < 0;
        return 1;
    } catch (...) {
        return 0;
    }
}
