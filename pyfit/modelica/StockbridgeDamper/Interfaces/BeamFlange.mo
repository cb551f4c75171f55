within StockbridgeDamper.Interfaces;
connector BeamFlange "Planar beam node: vertical displacement and rotation, with shear force and bending moment"
  Real x(unit="m") "Vertical displacement of the node";
  Real phi(unit="rad") "Rotation of the cross-section (small angle, positive counter-clockwise)";
  flow Real f(unit="N") "Vertical cut force, positive when it acts on the component upward";
  flow Real tau(unit="N.m") "Cut moment, positive when it acts on the component counter-clockwise";
end BeamFlange;
