within StockbridgeDamper.Components;
model Spring "Linear spring"
  extends Interfaces.PartialCompliant;
  parameter Real k(unit="N/m", min=0) = 1 "Spring stiffness";
equation
  f = k*s_rel;
end Spring;
