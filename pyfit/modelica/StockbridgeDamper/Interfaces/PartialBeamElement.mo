within StockbridgeDamper.Interfaces;
partial model PartialBeamElement "Two-node planar beam element with node variables in scalar form"
  BeamFlange flange_a "Node at the element's start (axial coordinate 0)";
  BeamFlange flange_b "Node at the element's end (axial coordinate L)";
  Real xa(unit="m", nominal=1e-4) "Vertical displacement of node a";
  Real pa(unit="rad", nominal=1e-3) "Rotation of node a";
  Real xb(unit="m", nominal=1e-4) "Vertical displacement of node b";
  Real pb(unit="rad", nominal=1e-3) "Rotation of node b";
equation
  xa = flange_a.x;
  pa = flange_a.phi;
  xb = flange_b.x;
  pb = flange_b.phi;
end PartialBeamElement;
