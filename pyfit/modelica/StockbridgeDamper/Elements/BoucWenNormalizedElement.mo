within StockbridgeDamper.Elements;
model BoucWenNormalizedElement "Normalised Bouc-Wen element (theory §1.3 form) between ground and a driven point: relative motion s, v in; force on the driven point out"
  parameter Real k_bw(unit="N/m") = 300 "Stiffness of the element";
  parameter Real a_bw(unit="1", min=0, max=1) = 0.3 "Weight of the linear (elastic) part";
  parameter Real A(unit="1") = 1 "Shape parameter of the hysteretic variable";
  parameter Real beta(unit="1", min=0) = 0.6 "Shape parameter multiplying |v|*|z|^(nu-1)*z";
  parameter Real gamma(unit="1") = 0.4 "Shape parameter multiplying v*|z|^nu";
  parameter Real nu(unit="1", min=1) = 1 "Exponent controlling the sharpness of the transition";
  parameter Real D(unit="m", min=0) = 1e-3 "Yield-like displacement scale";
  input Real s(unit="m", start=0) "Displacement of the driven point relative to the ground point";
  input Real v(unit="m/s", start=0) "Time derivative of s";
  output Real f(unit="N") "Force the element applies to the driven point";
  output Real df(unit="N/s") "Time derivative of f (for input extrapolation by a co-simulation master)";
  output Real z(unit="1") "Dimensionless hysteretic variable";
  Components.BoucWenNormalized boucWen(k_bw=k_bw, a_bw=a_bw, A=A, beta=beta, gamma=gamma, nu=nu, D=D) "Hysteretic element";
  Components.Fixed fixed "Ground point";
  Sources.Position position "Driven point";
equation
  position.s = s;
  connect(fixed.flange, boucWen.flange_a);
  connect(boucWen.flange_b, position.flange);
  f = -boucWen.f;
  df = -k_bw*(a_bw*v + (1 - a_bw)*D*der(boucWen.z));
  z = boucWen.z;
  annotation(__pyfit(inputDerivatives="s:v"), experiment(StartTime=0, StopTime=1, Interval=1e-4, Tolerance=1e-8));
end BoucWenNormalizedElement;
