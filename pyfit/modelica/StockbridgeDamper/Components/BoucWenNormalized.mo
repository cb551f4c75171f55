within StockbridgeDamper.Components;
model BoucWenNormalized "Normalised Bouc-Wen element: f = k_bw*(a_bw*s_rel + (1 - a_bw)*D*z), dz/dt = (A*v - beta*|v|*|z|^(nu-1)*z - gamma*v*|z|^nu)/D"
  extends Interfaces.PartialCompliant;
  parameter Real k_bw(unit="N/m") = 300 "Stiffness of the element; 0 switches it off";
  parameter Real a_bw(unit="1") = 0.3 "Weight of the linear (elastic) part, between 0 and 1";
  parameter Real A(unit="1") = 1 "Shape parameter of the hysteretic variable";
  parameter Real beta(unit="1") = 0.6 "Shape parameter multiplying |v|*|z|^(nu-1)*z";
  parameter Real gamma(unit="1") = 0.4 "Shape parameter multiplying v*|z|^nu";
  parameter Real nu(unit="1") = 1 "Exponent controlling the sharpness of the transition (nu >= 1)";
  parameter Real D(unit="m") = 1e-3 "Yield-like displacement scale";
  Real z(unit="1", start=0, nominal=1) "Dimensionless hysteretic variable";
equation
  der(z) = (A*v_rel - beta*abs(v_rel)*sign(z)*abs(z)^nu - gamma*v_rel*abs(z)^nu)/D;
  f = k_bw*(a_bw*s_rel + (1 - a_bw)*D*z);
end BoucWenNormalized;
