within StockbridgeDamper.Sources;
model BaseMotion "Shaker: prescribes the vertical motion of a beam node and holds its rotation at zero"
  input Real s(unit="m") "Prescribed vertical displacement (its first and second time derivatives must be known to the model: see the example's __pyfit annotation)";
  Interfaces.BeamFlange flange "Node driven by the shaker; -flange.f is the force the shaker applies";
  Real F(unit="N") "Force the shaker applies to the node, positive upward";
equation
  flange.x = s;
  flange.phi = 0;
  F = -flange.f;
end BaseMotion;
