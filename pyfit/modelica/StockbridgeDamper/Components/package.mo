within StockbridgeDamper;
package Components "Masses, springs, dampers, hysteretic and nonlinear elements, beam elements"
end Components;
