within StockbridgeDamper.Components;
model Damper "Linear viscous damper"
  extends Interfaces.PartialCompliant;
  parameter Real c(unit="N.s/m", min=0) = 0 "Damping coefficient";
equation
  f = c*v_rel;
end Damper;
