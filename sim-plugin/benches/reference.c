/* Plain-C reference for sim-plugin/benches/step.rs: the same one-block world and push
 * (docs/spec/world.md §2–§5), stepped directly with libode, to measure what the Rust
 * layers cost on this machine. It also prints the pushed block's outcome so
 * the two implementations can be compared number for number.
 *
 *   cc -O2 sim-plugin/benches/reference.c -lode -lm -o target/ode-reference
 *   target/ode-reference            # one_block, x0 = 0.105, 200 runs
 */
#include <ode/ode.h>
#include <math.h>
#include <stdio.h>
#include <time.h>

static dWorldID world;
static dSpaceID space;
static dJointGroupID group;
static dBodyID actuator, block;
/* mu1, mu2 per geom, via geom data: 0 ground, 1 actuator, 2 block */
static const double MU[3][2] = {{100, 50}, {0.01, 0.01}, {0.9, 0.9}};

static void near(void *data, dGeomID g1, dGeomID g2) {
  (void)data;
  dBodyID b1 = dGeomGetBody(g1), b2 = dGeomGetBody(g2);
  if (!b1 && !b2) return;
  dContactGeom cg[10];
  int n = dCollide(g1, g2, 10, cg, sizeof(dContactGeom));
  if (n <= 0) return;
  size_t i1 = (size_t)dGeomGetData(g1), i2 = (size_t)dGeomGetData(g2);
  double h = 0.001, kp = 1.0 / (1.0 / 1e12 + 1.0 / 1e12), kd = 2.0;
  dContact c;
  c.surface.mode = dContactApprox1 | dContactMu2 | dContactSoftERP | dContactSoftCFM |
                   dContactBounce | dContactSlip1 | dContactSlip2;
  c.surface.mu = fmin(MU[i1][0], MU[i2][0]);
  c.surface.mu2 = fmin(MU[i1][1], MU[i2][1]);
  c.surface.bounce = 0; c.surface.bounce_vel = 0;
  c.surface.slip1 = 0; c.surface.slip2 = 0;
  c.surface.soft_erp = h * kp / (h * kp + kd);
  c.surface.soft_cfm = 1.0 / (h * kp + kd);
  for (int i = 0; i < n; i++) {
    if (cg[i].depth < 0) continue;
    c.geom = cg[i];
    dJointID j = dJointCreateContact(world, group, &c);
    dJointAttach(j, b1, b2);
  }
}

static void place(dBodyID b, double x, double y, double z) {
  dQuaternion q = {1, 0, 0, 0};
  dBodySetPosition(b, x, y, z);
  dBodySetQuaternion(b, q);
  dBodySetLinearVel(b, 0, 0, 0); dBodySetAngularVel(b, 0, 0, 0);
  dBodySetForce(b, 0, 0, 0); dBodySetTorque(b, 0, 0, 0);
  dBodySetAutoDisableAverageSamplesCount(b, 1);
  dBodyEnable(b);
}

static void step(const double dir[3]) {
  const dReal *p = dBodyGetPosition(actuator);
  dBodyEnable(actuator);
  dBodySetAngularVel(actuator, 0, 0, 0);
  dBodySetLinearVel(actuator, dir[0], dir[1], dir[2]);
  dBodySetPosition(actuator, p[0], p[1], 0.03);
  dSpaceCollide(space, 0, near);
  dWorldQuickStep(world, 0.001);
  dJointGroupEmpty(group);
}

int main(void) {
  dInitODE2(0);
  dAllocateODEDataForThread(dAllocateMaskAll);
  world = dWorldCreate();
  dWorldSetGravity(world, 0, 0, -9.81);
  dWorldSetERP(world, 0.2); dWorldSetCFM(world, 0);
  dWorldSetQuickStepNumIterations(world, 50); dWorldSetQuickStepW(world, 1.3);
  dWorldSetContactMaxCorrectingVel(world, 100); dWorldSetContactSurfaceLayer(world, 0.001);
  dWorldSetDamping(world, 1e-4, 1e-4);
  dWorldSetAutoDisableFlag(world, 1); dWorldSetAutoDisableTime(world, 1.0);
  dWorldSetAutoDisableLinearThreshold(world, 0.1); dWorldSetAutoDisableAngularThreshold(world, 0.1);
  dWorldSetAutoDisableSteps(world, 5);
  space = dSimpleSpaceCreate(0);
  group = dJointGroupCreate(0);
  dGeomSetData(dCreatePlane(space, 0, 0, 1, 0), (void *)0);
  dMass m;
  actuator = dBodyCreate(world);
  dMassSetZero(&m); dMassSetParameters(&m, 10, 0, 0, 0, 2.5e-4, 2.5e-4, 2.5e-4, 0, 0, 0);
  dBodySetMass(actuator, &m); dBodySetGravityMode(actuator, 0);
  dGeomID gs = dCreateSphere(space, 0.025); dGeomSetBody(gs, actuator); dGeomSetData(gs, (void *)1);
  block = dBodyCreate(world);
  dMassSetZero(&m); dMassSetParameters(&m, 1, 0, 0, 0, 1.66667e-3, 0.0216667, 0.0216667, 0, 0, 0);
  dBodySetMass(block, &m);
  dGeomID gb = dCreateBox(space, 0.5, 0.1, 0.1); dGeomSetBody(gb, block); dGeomSetData(gb, (void *)2);

  const int runs = 200, steps = 1500;
  const double x0 = 0.105, dir[3] = {0, 0.5, 0};
  struct timespec t0, t1;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  for (int r = 0; r < runs; r++) {
    place(actuator, 0, 0, 0.03);
    place(block, 0, 0.25, 0.05);
    dRandSetSeed(0);
    place(actuator, x0, 0, 0.03);
    for (int s = 0; s < steps; s++) step(dir);
  }
  clock_gettime(CLOCK_MONOTONIC, &t1);
  double secs = (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec);
  const dReal *p = dBodyGetPosition(block), *q = dBodyGetQuaternion(block);
  double yaw = atan2(2 * (q[0] * q[3] + q[1] * q[2]), 1 - 2 * (q[2] * q[2] + q[3] * q[3]));
  printf("block after the push from x0 = %.3f: x %.4f y %.4f yaw %.4f\n", x0, p[0], p[1], yaw);
  printf("%.2f us/step (%.0f steps/s) over %d steps\n", 1e6 * secs / (runs * steps),
         runs * steps / secs, runs * steps);
  return 0;
}
