within StockbridgeDamper.Components;
model SpringDamper "Linear spring and viscous damper in parallel"
  extends Interfaces.PartialCompliant;
  parameter Real k(unit="N/m", min=0) = 1 "Spring stiffness";
  parameter Real c(unit="N.s/m", min=0) = 0 "Damping coefficient";
equation
  f = k*s_rel + c*v_rel;
end SpringDamper;
