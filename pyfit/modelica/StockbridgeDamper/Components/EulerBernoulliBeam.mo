within StockbridgeDamper.Components;
model EulerBernoulliBeam "Planar Euler-Bernoulli beam element: consistent mass and stiffness matrices, Rayleigh damping on the deformation"
  extends Interfaces.PartialBeamElement;
  parameter Real EI(unit="N.m2", min=0) = 10 "Flexural rigidity";
  parameter Real mu(unit="kg/m", min=0) = 0.3 "Mass per unit length";
  parameter Real L(unit="m", min=0) = 0.1 "Element length";
  parameter Real alpha_pd(unit="1/s") = 0 "Mass-proportional Rayleigh damping coefficient";
  parameter Real beta_pd(unit="s") = 0 "Stiffness-proportional Rayleigh damping coefficient";
  Interfaces.BeamFlange support "Reference frame of the damping (connect to the clamp): mass-proportional damping acts on velocities relative to its vertical motion and its reaction acts on it";
  Real va(unit="m/s", start=0, nominal=1e-2) "Vertical velocity of node a";
  Real wa(unit="rad/s", start=0, nominal=1e-1) "Angular velocity of node a";
  Real vb(unit="m/s", start=0, nominal=1e-2) "Vertical velocity of node b";
  Real wb(unit="rad/s", start=0, nominal=1e-1) "Angular velocity of node b";
  Real aa(unit="m/s2") "Vertical acceleration of node a";
  Real ala(unit="rad/s2") "Angular acceleration of node a";
  Real ab(unit="m/s2") "Vertical acceleration of node b";
  Real alb(unit="rad/s2") "Angular acceleration of node b";
  Real vs(unit="m/s") "Vertical velocity of the damping reference frame";
  Real fda(unit="N") "Mass-proportional damping force at node a (vertical)";
  Real fdb(unit="N") "Mass-proportional damping force at node b (vertical)";
  Real tda(unit="N.m") "Mass-proportional damping moment at node a";
  Real tdb(unit="N.m") "Mass-proportional damping moment at node b";
protected
  parameter Real ck(unit="N/m") = EI/L^3 "Stiffness scale EI/L^3";
  parameter Real cm(unit="kg") = mu*L/420 "Consistent mass scale mu*L/420";
equation
  va = der(xa);
  wa = der(pa);
  vb = der(xb);
  wb = der(pb);
  aa = der(va);
  ala = der(wa);
  ab = der(vb);
  alb = der(wb);
  vs = der(support.x);
  // mass-proportional damping: alpha_pd*M_e*(qdot - T*vs), T = rigid translation {1, 0, 1, 0}
  fda = alpha_pd*cm*(156*(va - vs) + 22*L*wa + 54*(vb - vs) - 13*L*wb);
  tda = alpha_pd*cm*(22*L*(va - vs) + 4*L^2*wa + 13*L*(vb - vs) - 3*L^2*wb);
  fdb = alpha_pd*cm*(54*(va - vs) + 13*L*wa + 156*(vb - vs) - 22*L*wb);
  tdb = alpha_pd*cm*(-13*L*(va - vs) - 3*L^2*wa - 22*L*(vb - vs) + 4*L^2*wb);
  // nodal forces = M_e*qddot + K_e*(q + beta_pd*qdot) + damping
  flange_a.f = cm*(156*aa + 22*L*ala + 54*ab - 13*L*alb)
    + ck*(12*(xa + beta_pd*va) + 6*L*(pa + beta_pd*wa) - 12*(xb + beta_pd*vb) + 6*L*(pb + beta_pd*wb)) + fda;
  flange_a.tau = cm*(22*L*aa + 4*L^2*ala + 13*L*ab - 3*L^2*alb)
    + ck*(6*L*(xa + beta_pd*va) + 4*L^2*(pa + beta_pd*wa) - 6*L*(xb + beta_pd*vb) + 2*L^2*(pb + beta_pd*wb)) + tda;
  flange_b.f = cm*(54*aa + 13*L*ala + 156*ab - 22*L*alb)
    + ck*(-12*(xa + beta_pd*va) - 6*L*(pa + beta_pd*wa) + 12*(xb + beta_pd*vb) - 6*L*(pb + beta_pd*wb)) + fdb;
  flange_b.tau = cm*(-13*L*aa - 3*L^2*ala - 22*L*ab + 4*L^2*alb)
    + ck*(6*L*(xa + beta_pd*va) + 2*L^2*(pa + beta_pd*wa) - 6*L*(xb + beta_pd*vb) + 4*L^2*(pb + beta_pd*wb)) + tdb;
  support.f = -(fda + fdb);
  support.tau = 0;
end EulerBernoulliBeam;
