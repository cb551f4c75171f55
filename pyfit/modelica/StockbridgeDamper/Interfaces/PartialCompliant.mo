within StockbridgeDamper.Interfaces;
partial model PartialCompliant "Force element between two translational flanges acting on the relative motion"
  Flange flange_a "Left flange (support side)";
  Flange flange_b "Right flange (driven side)";
  Real s_rel(unit="m") "Relative displacement flange_b.s - flange_a.s";
  Real v_rel(unit="m/s") "Relative velocity der(s_rel)";
  Real f(unit="N") "Force transmitted by the element (tension positive): flange_b.f = f, flange_a.f = -f";
equation
  s_rel = flange_b.s - flange_a.s;
  v_rel = der(s_rel);
  flange_b.f = f;
  flange_a.f = -f;
end PartialCompliant;
