within StockbridgeDamper.Components;
model Clamp "Rigid clamp body at a beam node: mass and moment of inertia about the node"
  parameter Real m(unit="kg", min=0) = 0.6 "Clamp mass";
  parameter Real J(unit="kg.m2", min=0) = 2.5e-4 "Clamp moment of inertia about the node";
  Interfaces.BeamFlange flange "Node the clamp is attached to (connect the cable and the shaker here)";
  Real x(unit="m", start=0, nominal=1e-4) "Vertical displacement of the clamp";
  Real phi(unit="rad", start=0, nominal=1e-3) "Rotation of the clamp";
  Real v(unit="m/s", start=0, nominal=1e-2) "Vertical velocity of the clamp";
  Real w(unit="rad/s", start=0, nominal=1e-1) "Angular velocity of the clamp";
  Real acc(unit="m/s2") "Vertical acceleration of the clamp";
  Real alp(unit="rad/s2") "Angular acceleration of the clamp";
equation
  x = flange.x;
  phi = flange.phi;
  v = der(x);
  w = der(phi);
  acc = der(v);
  alp = der(w);
  flange.f = m*acc;
  flange.tau = J*alp;
end Clamp;
