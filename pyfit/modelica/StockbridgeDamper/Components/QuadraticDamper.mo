within StockbridgeDamper.Components;
model QuadraticDamper "Quadratic (drag-like) damping: f = c2*v_rel*|v_rel|; c2 = 0 switches it off"
  extends Interfaces.PartialCompliant;
  parameter Real c2(unit="N.s2/m2") = 0 "Quadratic damping coefficient";
equation
  f = c2*v_rel*abs(v_rel);
end QuadraticDamper;
