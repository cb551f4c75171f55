within StockbridgeDamper.Elements;
model BoucWenElement "Bouc-Wen element (theory §1.1 form) between ground and a driven point: relative motion s, v in; force on the driven point out"
  parameter Real alpha(unit="N/m") = 5e4 "Initial (tangent) stiffness of the hysteretic force";
  parameter Real beta = 1e3 "Scale of the nonlinear terms, unit m^-nu (1/m for nu = 1)";
  parameter Real gamma = 0.8 "Shape parameter multiplying |v|*|z|^(nu-1)*z";
  parameter Real delta = -1.1 "Shape parameter multiplying v*|z|^nu";
  parameter Real nu(min=1) = 1 "Exponent controlling the sharpness of the transition";
  input Real s(unit="m", start=0) "Displacement of the driven point relative to the ground point";
  input Real v(unit="m/s", start=0) "Time derivative of s";
  output Real f(unit="N") "Force the element applies to the driven point (= -z)";
  output Real df(unit="N/s") "Time derivative of f (for input extrapolation by a co-simulation master)";
  output Real z(unit="N") "Hysteretic force";
  Components.BoucWen boucWen(alpha=alpha, beta=beta, gamma=gamma, delta=delta, nu=nu) "Hysteretic element";
  Components.Fixed fixed "Ground point";
  Sources.Position position "Driven point";
equation
  position.s = s;
  connect(fixed.flange, boucWen.flange_a);
  connect(boucWen.flange_b, position.flange);
  f = -boucWen.f;
  df = -der(boucWen.z);
  z = boucWen.z;
  annotation(__pyfit(inputDerivatives="s:v"), experiment(StartTime=0, StopTime=1, Interval=1e-4, Tolerance=1e-8));
end BoucWenElement;
