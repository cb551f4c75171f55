within StockbridgeDamper.Components;
model CubicSpring "Cubic (geometric) stiffness: f = k3*s_rel^3; k3 < 0 softens, k3 = 0 switches it off"
  extends Interfaces.PartialCompliant;
  parameter Real k3(unit="N/m3") = 0 "Cubic stiffness coefficient";
equation
  f = k3*s_rel^3;
end CubicSpring;
