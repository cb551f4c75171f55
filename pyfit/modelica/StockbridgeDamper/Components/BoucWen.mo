within StockbridgeDamper.Components;
model BoucWen "Classic Bouc-Wen hysteretic element: f = z, dz/dt = alpha*v - beta*(gamma*|v|*|z|^(nu-1)*z + delta*v*|z|^nu)"
  extends Interfaces.PartialCompliant;
  parameter Real alpha(unit="N/m") = 5e4 "Initial (tangent) stiffness of the hysteretic force; 0 switches the element off";
  parameter Real beta = 1e3 "Scale of the nonlinear terms, unit m^-nu (1/m for nu = 1)";
  parameter Real gamma = 0.8 "Shape parameter multiplying |v|*|z|^(nu-1)*z";
  parameter Real delta = -1.1 "Shape parameter multiplying v*|z|^nu";
  parameter Real nu = 1 "Exponent controlling the sharpness of the transition (nu >= 1)";
  Real z(unit="N", start=0, nominal=1) "Hysteretic force";
equation
  der(z) = alpha*v_rel - beta*(gamma*abs(v_rel)*sign(z)*abs(z)^nu + delta*v_rel*abs(z)^nu);
  f = z;
end BoucWen;
